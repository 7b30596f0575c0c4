// Sobel gradient magnitude over u_channels channels, divided by 4 so a unit step gives 1.
// u_threshold > 0 makes it binary (1 above it), u_invert draws dark edges on white.
#include "_fetch.glsl"

uniform sampler2D u_source;
uniform float u_threshold;
uniform int u_channels;
uniform bool u_invert;

out vec4 o_value;

vec4 f(ivec2 p, int dx, int dy) {
    return fetch(u_source, p + ivec2(dx, dy));
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 mask = vec4(greaterThan(ivec4(u_channels), ivec4(0, 1, 2, 3)));
    vec4 gx = (f(p, 1, -1) + 2.0 * f(p, 1, 0) + f(p, 1, 1)) - (f(p, -1, -1) + 2.0 * f(p, -1, 0) + f(p, -1, 1));
    vec4 gy = (f(p, -1, 1) + 2.0 * f(p, 0, 1) + f(p, 1, 1)) - (f(p, -1, -1) + 2.0 * f(p, 0, -1) + f(p, 1, -1));
    gx *= mask;
    gy *= mask;
    float g = 0.25 * sqrt(dot(gx, gx) + dot(gy, gy));
    float e = u_threshold > 0.0 ? float(g > u_threshold) : g;
    e = u_invert ? 1.0 - e : e;
    o_value = vec4(e, e, e, 1.0);
}

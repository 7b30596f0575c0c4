// Roberts cross: |f(x,y) - f(x+1,y+1)| + |f(x+1,y) - f(x,y+1)|, |.| the length over u_channels
// channels. u_threshold > 0 makes it binary (1 above it), u_invert draws dark edges on white.
#include "_fetch.glsl"

uniform sampler2D u_source;
uniform float u_threshold;
uniform int u_channels;
uniform bool u_invert;

out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 mask = vec4(greaterThan(ivec4(u_channels), ivec4(0, 1, 2, 3)));
    float g = length((fetch(u_source, p) - fetch(u_source, p + ivec2(1, 1))) * mask)
            + length((fetch(u_source, p + ivec2(1, 0)) - fetch(u_source, p + ivec2(0, 1))) * mask);
    float e = u_threshold > 0.0 ? float(g > u_threshold) : g;
    e = u_invert ? 1.0 - e : e;
    o_value = vec4(e, e, e, 1.0);
}

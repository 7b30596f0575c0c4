// Deferred toon shading: the Lambert term quantised to u_bands levels,
// q = min(floor(d * bands), bands - 1) / (bands - 1); u_background where there is no surface.
#include "_shade.glsl"

uniform int u_bands;

out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float d = diffuse(p);
    if (d < 0.0) {
        o_value = background();
        return;
    }
    float q = min(floor(d * float(u_bands)), float(u_bands - 1)) / float(u_bands - 1);
    vec4 c = texelFetch(u_color, p, 0);
    o_value = vec4(c.rgb * (u_ambient + (1.0 - u_ambient) * q), 1.0);
}

// Deferred Lambert shading: colour * (ambient + (1 - ambient) max(n.l, 0)); u_background where
// there is no surface.
#include "_shade.glsl"

out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float d = diffuse(p);
    if (d < 0.0) {
        o_value = background();
        return;
    }
    vec4 c = texelFetch(u_color, p, 0);
    o_value = vec4(c.rgb * (u_ambient + (1.0 - u_ambient) * d), 1.0);
}

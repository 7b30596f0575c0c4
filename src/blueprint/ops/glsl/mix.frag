// Blend two images of one size: r = mode(a, b), then a * (1 - factor) + r * factor.
// A one-channel input counts as grey: (v, v, v, 1).
uniform sampler2D u_a;
uniform sampler2D u_b;
uniform int u_a_components;
uniform int u_b_components;
uniform int u_mode;  // mix, multiply, add, subtract, min, max, screen
uniform float u_factor;

out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 a = texelFetch(u_a, p, 0);
    vec4 b = texelFetch(u_b, p, 0);
    a = u_a_components == 1 ? vec4(a.rrr, 1.0) : a;
    b = u_b_components == 1 ? vec4(b.rrr, 1.0) : b;
    vec4 r = b;
    if (u_mode == 1) {
        r = a * b;
    } else if (u_mode == 2) {
        r = a + b;
    } else if (u_mode == 3) {
        r = a - b;
    } else if (u_mode == 4) {
        r = min(a, b);
    } else if (u_mode == 5) {
        r = max(a, b);
    } else if (u_mode == 6) {
        r = 1.0 - (1.0 - a) * (1.0 - b);
    }
    o_value = a * (1.0 - u_factor) + r * u_factor;
}

// One direction of a separable Gaussian blur; the executor runs it along x, then along y.
// Weights (normalised, centre first) come from the descriptor; the image edge is clamped.
#include "_fetch.glsl"

uniform sampler2D u_source;
uniform ivec2 u_direction;
uniform int u_radius;
uniform float u_weights[49];

out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 sum = u_weights[0] * fetch(u_source, p);
    for (int i = 1; i <= u_radius; ++i) {
        sum += u_weights[i] * (fetch(u_source, p + i * u_direction) + fetch(u_source, p - i * u_direction));
    }
    o_value = sum;
}

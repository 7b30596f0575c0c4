// The largest value of each 4x4 block of the input: the counting pass's maximum, reduced on
// the GPU so that a few texels are read back instead of the whole frame.
uniform sampler2D u_values;

out vec4 o_max;

void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * 4;
    ivec2 last = textureSize(u_values, 0) - 1;
    float m = 0.0;
    for (int y = 0; y < 4; ++y) {
        for (int x = 0; x < 4; ++x) {
            m = max(m, texelFetch(u_values, min(base + ivec2(x, y), last), 0).r);
        }
    }
    o_max = vec4(m);
}

// Shrink by an integer factor (the ratio of input to output size, set by the executor):
// box, the mean of each factor x factor block; or Gaussian, sigma = factor / 2 about the
// block's centre, taps out to half a block beyond it, edge clamped.
#include "_fetch.glsl"

uniform sampler2D u_source;
uniform int u_source_factor;
uniform int u_filter;  // 0 box, 1 gaussian

out vec4 o_value;

void main() {
    int f = u_source_factor;
    ivec2 base = ivec2(gl_FragCoord.xy) * f;
    vec4 sum = vec4(0.0);
    if (u_filter == 0) {
        for (int y = 0; y < f; ++y) {
            for (int x = 0; x < f; ++x) {
                sum += fetch(u_source, base + ivec2(x, y));
            }
        }
        o_value = sum / float(f * f);
        return;
    }
    int h = (f + 1) / 2;
    float centre = 0.5 * float(f - 1);
    float k = 2.0 / float(f * f);  // 1 / (2 sigma^2), sigma = f / 2
    float total = 0.0;
    for (int y = -h; y < f + h; ++y) {
        float wy = exp(-k * (float(y) - centre) * (float(y) - centre));
        for (int x = -h; x < f + h; ++x) {
            float w = wy * exp(-k * (float(x) - centre) * (float(x) - centre));
            sum += w * fetch(u_source, base + ivec2(x, y));
            total += w;
        }
    }
    o_value = sum / total;
}

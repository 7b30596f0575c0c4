// Grey-scale dilation by a disc: thicker lines with a soft one-pixel rim; narrower (fainter)
// ones on hidden layers (_widths.glsl).
#include "_widths.glsl"
uniform sampler2D u_source;
uniform int u_layer;

out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(u_source, 0) - 1;
    vec2 width = layer_width(u_layer);
    int r = int(ceil(width.x));
    float v = 0.0;
    for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
            float weight = clamp(width.x + 1.0 - length(vec2(dx, dy)), 0.0, 1.0);
            ivec2 q = clamp(p + ivec2(dx, dy), ivec2(0), last);
            v = max(v, weight * texelFetch(u_source, q, 0).r);
        }
    }
    o_value = vec4(v * width.y);
}

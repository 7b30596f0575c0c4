// Depth-sprite composition of up to 8 edge layers (4 per RGBA texture, one layer per channel),
// back to front, each weighted by its ink's opacity; the box filter over the supersampled
// edge maps gives anti-aliased lines. Output is premultiplied, blended over what is there.
uniform sampler2D u_edges0;
uniform sampler2D u_edges1;
uniform int u_layers;        // layers of these two textures that take part
// SUPERSAMPLE (a define): edge-map pixels per output pixel along each axis, so loops unroll
uniform bool u_threshold;    // wire-frame variant: binary edges
uniform vec4 u_ink[8];       // straight colour and opacity per layer
uniform bool u_shaded;

out vec4 o_color;

#include "shaded_layers.glsl"

float edge_at(int k, ivec2 q) {
    vec4 e = k < 4 ? texelFetch(u_edges0, q, 0) : texelFetch(u_edges1, q, 0);
    float v = e[k & 3];
    return u_threshold ? step(0.5, v) : v;
}

void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * SUPERSAMPLE;
    if (u_shaded) {
        vec4 sum = vec4(0.0);
        for (int y = 0; y < SUPERSAMPLE; ++y) {
            for (int x = 0; x < SUPERSAMPLE; ++x) {
                vec4 sample_color;
                SHADED_COMPOSITE(edge_at, u_layers, u_ink, base + ivec2(x, y), sample_color)
                sum += sample_color;
            }
        }
        o_color = sum / float(SUPERSAMPLE * SUPERSAMPLE);
        return;
    }
    vec4 c0 = vec4(0.0);
    vec4 c1 = vec4(0.0);
    for (int y = 0; y < SUPERSAMPLE; ++y) {
        for (int x = 0; x < SUPERSAMPLE; ++x) {
            vec4 e0 = texelFetch(u_edges0, base + ivec2(x, y), 0);
            vec4 e1 = u_layers > 4 ? texelFetch(u_edges1, base + ivec2(x, y), 0) : vec4(0.0);
            if (u_threshold) {
                e0 = step(0.5, e0);
                e1 = step(0.5, e1);
            }
            c0 += e0;
            c1 += e1;
        }
    }
    float norm = 1.0 / float(SUPERSAMPLE * SUPERSAMPLE);
    float coverage[8] = float[8](c0.x, c0.y, c0.z, c0.w, c1.x, c1.y, c1.z, c1.w);
    vec3 color = vec3(0.0);
    float alpha = 0.0;
    for (int k = 7; k >= 0; --k) {
        if (k < u_layers) {
            float a = clamp(coverage[k] * norm, 0.0, 1.0) * u_ink[k].a;
            color = u_ink[k].rgb * a + color * (1.0 - a);
            alpha = a + alpha * (1.0 - a);
        }
    }
    o_color = vec4(color, alpha);
}

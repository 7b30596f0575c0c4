// Depth-sprite composition of the edge array (up to 8 slices a dispatch), back to front, each
// layer weighted by its ink's opacity; at each supersample the strongest line wins
// (lines.glsl), and the box filter over the supersampled edge maps gives anti-aliased lines.
// The first (back-most) dispatch starts from the paper, later ones blend over what the earlier
// ones wrote. Premultiplied alpha throughout. With OVERLAY the edges are one 2D map (the
// highlighted parts' outline) laid over everything. The same arithmetic as composite.frag.
layout(local_size_x = 8, local_size_y = 8) in;
#include "paper.glsl"

#if OVERLAY
uniform sampler2D u_edges;
#define EDGE(q, k) texelFetch(u_edges, q, 0).r
#define EDGES_2X2(at, k) textureGather(u_edges, at)
#else
uniform sampler2DArray u_edges;
#define EDGE(q, k) texelFetch(u_edges, ivec3(q, k), 0).r
#define EDGES_2X2(at, k) textureGather(u_edges, vec3(at, k))
#endif
layout(rgba8, binding = 0) uniform image2D u_out;
uniform int u_layers;
uniform int u_supersample;
uniform bool u_threshold;   // wire-frame variant: binary edges
uniform bool u_first;
uniform bool u_has_paper;
uniform vec4 u_ink[8];      // straight colour and opacity per layer
uniform bool u_shaded;

#include "lines.glsl"
#include "shaded_layers.glsl"

float edge_at(int k, ivec2 q) {
    float v = EDGE(q, k);
    return u_threshold ? step(0.5, v) : v;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThan(p, imageSize(u_out) - 1))) {
        return;
    }
    vec4 color;
    if (u_first) {
        color = u_has_paper ? paper_color(vec2(p) + 0.5) : vec4(0.0);
    } else {
        color = imageLoad(u_out, p);
    }
    ivec2 base = p * u_supersample;
    float norm = 1.0 / float(u_supersample * u_supersample);
    if (u_shaded) {
        vec4 sum = vec4(0.0);
        for (int y = 0; y < u_supersample; ++y) {
            for (int x = 0; x < u_supersample; ++x) {
                vec4 sample_color;
                SHADED_COMPOSITE(edge_at, u_layers, u_ink, base + ivec2(x, y), sample_color)
                sum += sample_color;
            }
        }
        imageStore(u_out, p, sum * norm + color * (1.0 - sum.a * norm));
        return;
    }
    vec4 lines = vec4(0.0);
    if (u_supersample == 2) {
        // the 2 x 2 samples of a layer in one gather, not four fetches (the composite is bound
        // by its reads on a GPU; llvmpipe's gathers cost more than its fetches, and
        // composite.frag keeps them): components w, z, x, y are
        // samples (0, 0), (1, 0), (0, 1), (1, 1), summed in the order of the loop below
        vec2 at = vec2(base + 1) / vec2(textureSize(u_edges, 0).xy);
        vec4 union_[4] = vec4[4](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
        for (int k = u_layers - 1; k >= 0; --k) {
            vec4 e = EDGES_2X2(at, k);
            vec4 a = clamp(u_threshold ? step(0.5, e) : e, 0.0, 1.0) * u_ink[k].a;
            union_[0] = strongest(union_[0], u_ink[k].rgb, a.w);
            union_[1] = strongest(union_[1], u_ink[k].rgb, a.z);
            union_[2] = strongest(union_[2], u_ink[k].rgb, a.x);
            union_[3] = strongest(union_[3], u_ink[k].rgb, a.y);
        }
        lines = (((union_[0] + union_[1]) + union_[2]) + union_[3]) * norm;
        imageStore(u_out, p, lines + color * (1.0 - lines.a));
        return;
    }
    for (int y = 0; y < u_supersample; ++y) {
        for (int x = 0; x < u_supersample; ++x) {
            vec4 union_ = vec4(0.0);
            for (int k = u_layers - 1; k >= 0; --k) {
                float a = clamp(edge_at(k, base + ivec2(x, y)), 0.0, 1.0) * u_ink[k].a;
                union_ = strongest(union_, u_ink[k].rgb, a);
            }
            lines += union_;
        }
    }
    lines *= norm;
    imageStore(u_out, p, lines + color * (1.0 - lines.a));
}

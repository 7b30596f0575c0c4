// The edges operation (edges.glsl) on one depth layer read straight from the A-buffer's sorted
// lists (blueprint.render:glsl/abuffer.glsl), as a fragment pass over the layer's tiles: what
// a software rasteriser draws instead of unpacking each layer into the G-buffer first (the
// unpack wrote three targets a pixel that this pass read back at once). u_from holds each
// pixel's node of this layer + 1, u_next gets the one of the next layer: the pixels drawn at a
// layer are drawn at every layer before it (a tile's layers only shrink), so u_from is whole
// where this pass reads it but for pixels this layer does not cover, which it never reads (their
// layer counts say so). One node load gives a sample's depth, normal and IDs together.
#extension GL_ARB_shading_language_packing : require
#include "blueprint.render:glsl/kbuffer.glsl"
#include "blueprint.render:glsl/abuffer.glsl"

layout(r32ui, binding = 2) uniform readonly uimage2D u_from;
layout(r32ui, binding = 3) uniform writeonly uimage2D u_next;
layout(r32ui, binding = 4) uniform readonly uimage2D u_layer_count;  // each pixel's layers
uniform int u_layer;
uniform float u_back_bias;

#include "edges_held.glsl"
#define EDGE_LAST (imageSize(u_from) - 1)
#define EDGE_RING_COVERED(q, r) (imageLoad(u_layer_count, q).x > uint(u_layer))
#include "blueprint.ops:glsl/edges.glsl"

out vec4 o_edge;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = EDGE_LAST;
    // the counts first, every sample's at once: llvmpipe runs every lane through each load
    bool covered[5];
    covered[0] = imageLoad(u_layer_count, p).x > uint(u_layer);
    for (int i = 0; i < 4; ++i) {
        covered[i + 1] = imageLoad(u_layer_count, clamp(p + OFFSETS[i], ivec2(0), last)).x > uint(u_layer);
    }
    uint at[5];
    at[0] = covered[0] ? imageLoad(u_from, p).x : 0u;
    for (int i = 0; i < 4; ++i) {
        at[i + 1] = covered[i + 1] ? imageLoad(u_from, clamp(p + OFFSETS[i], ivec2(0), last)).x : 0u;
    }
    for (int i = 0; i < 5; ++i) {
        sample_depth[i] = 1.0;
        sample_normal[i] = vec3(0.0);
        sample_ids[i] = ivec2(0);
        if (at[i] != 0u) {
            uvec4 s = AB_NODE(at[i] - 1u);
            sample_depth[i] = kb_depth(s, u_back_bias);
            sample_normal[i] = kb_normal(s);
            sample_ids[i] = kb_ids(s);
        }
    }
    imageStore(u_next, p, uvec4(at[0] != 0u ? AB_ORDER(at[0] - 1u) : 0u));
    o_edge = vec4(layer_edge_value(p, u_layer));
}

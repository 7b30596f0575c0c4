// The edges operation (edges.glsl) on up to BATCH depth layers at once (u_layer and the
// u_batch - 1 behind it, one target each), read straight from the A-buffer's sorted lists
// (blueprint.render:glsl/abuffer.glsl), as a fragment pass over the first layer's tiles: what a
// software rasteriser draws instead of unpacking each layer into the G-buffer first (the
// unpack wrote three targets a pixel that this pass read back at once). u_from holds each
// pixel's node of layer u_layer, plus one, u_next gets the one of the layer after the batch: the
// pixels drawn at a layer are drawn at every layer before it (a tile's layers only shrink), so
// u_from is whole where this pass reads it but for pixels the layer does not cover, which it
// never reads (their layer counts say so). Each pixel walks its own chain and its four
// neighbours' side by side; one node load gives a sample's depth, normal and IDs together, and
// the layer counts (the pixel's, its neighbours', the ring's) and cursors are read once for
// the batch, not once a layer, which saves most in the deeper, sparser batches.
#extension GL_ARB_shading_language_packing : require
#include "blueprint.render:glsl/kbuffer.glsl"
#include "blueprint.render:glsl/abuffer.glsl"

layout(r32ui, binding = 2) uniform readonly uimage2D u_from;
layout(r32ui, binding = 3) uniform writeonly uimage2D u_next;
layout(r32ui, binding = 4) uniform readonly uimage2D u_layer_count;  // each pixel's layers
uniform int u_layer;  // the batch's first layer
uniform int u_batch;  // its layers, 1 to BATCH: outputs 0 to u_batch - 1
uniform float u_back_bias;

#include "edges_held.glsl"
#define EDGE_LAST (imageSize(u_from) - 1)
uint ring_count[8];
int ring_layer;  // the layer edge_value is looking at
#define EDGE_RING_COVERED(q, r) (ring_count[r] > uint(ring_layer))
#include "blueprint.ops:glsl/edges.glsl"

layout(location = 0) out vec4 o_edge0;
#if BATCH > 1
layout(location = 1) out vec4 o_edge1;
#endif
#if BATCH > 2
layout(location = 2) out vec4 o_edge2;
#endif
#if BATCH > 3
layout(location = 3) out vec4 o_edge3;
#endif
#if BATCH > 4
layout(location = 4) out vec4 o_edge4;
#endif
#if BATCH > 5
layout(location = 5) out vec4 o_edge5;
#endif
#if BATCH > 6
layout(location = 6) out vec4 o_edge6;
#endif
#if BATCH > 7
layout(location = 7) out vec4 o_edge7;
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = EDGE_LAST;
    // every count at once: llvmpipe runs every lane through each load
    uint counts[5];
    counts[0] = imageLoad(u_layer_count, p).x;
    for (int i = 0; i < 4; ++i) {
        counts[i + 1] = imageLoad(u_layer_count, clamp(p + OFFSETS[i], ivec2(0), last)).x;
    }
    for (int r = 0; r < 8; ++r) {
        ring_count[r] = imageLoad(u_layer_count, clamp(p + RING[r], ivec2(0), last)).x;
    }
    uint at[5];
    at[0] = counts[0] > uint(u_layer) ? imageLoad(u_from, p).x : 0u;
    for (int i = 0; i < 4; ++i) {
        at[i + 1] = counts[i + 1] > uint(u_layer) ? imageLoad(u_from, clamp(p + OFFSETS[i], ivec2(0), last)).x : 0u;
    }
    // A layer that none of the five holds has no edge here (edge_value's speck rule), nor does
    // any behind it: a pixel's lanes stop there. Tested at the loop's end, where a software
    // rasteriser leaves a loop once every lane has (a test at the top runs the body once more
    // with every lane masked off).
    uint deepest = max(max(max(counts[0], counts[1]), max(counts[2], counts[3])), counts[4]);
    float e[BATCH];
    for (int b = 0; b < BATCH; ++b) {
        e[b] = 0.0;
    }
    int b = 0;
    do {
        int layer = u_layer + b;
        if (uint(layer) >= deepest) {
            break;
        }
        for (int i = 0; i < 5; ++i) {
            sample_depth[i] = 1.0;
            sample_normal[i] = vec3(0.0);
            sample_ids[i] = ivec2(0);
            if (counts[i] > uint(layer)) {
                uvec4 s = AB_NODE(at[i] - 1u);
                sample_depth[i] = kb_depth(s, u_back_bias);
                sample_normal[i] = kb_normal(s);
                sample_ids[i] = kb_ids(s);
                at[i] = AB_ORDER(at[i] - 1u);
            }
        }
        ring_layer = layer;
        e[b] = layer_edge_value(p, layer);
        ++b;
    } while (b < u_batch);
    // the pixel's chain is read at the next batch only where it holds a layer there, and then
    // it held every layer of this one: its lane ran the whole batch
    imageStore(u_next, p, uvec4(at[0]));
    o_edge0 = vec4(e[0]);
#if BATCH > 1
    o_edge1 = vec4(e[1]);
#endif
#if BATCH > 2
    o_edge2 = vec4(e[2]);
#endif
#if BATCH > 3
    o_edge3 = vec4(e[3]);
#endif
#if BATCH > 4
    o_edge4 = vec4(e[4]);
#endif
#if BATCH > 5
    o_edge5 = vec4(e[5]);
#endif
#if BATCH > 6
    o_edge6 = vec4(e[6]);
#endif
#if BATCH > 7
    o_edge7 = vec4(e[7]);
#endif
}

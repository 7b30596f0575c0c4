// The edges operation (edges.glsl) on up to 8 depth layers at once, read straight from the
// A-buffer's sorted lists (blueprint.render:glsl/abuffer.glsl) instead of from each layer
// unpacked into the G-buffer: each pixel walks its own layer chain and its four neighbours'
// side by side, from where they stood at the array's first layer (u_from, the resolve's cursor
// for the first array), and leaves its own where the next array starts (u_next). The samples
// are those the unpack would have written: a pixel past its last layer has depth 1, its normal
// and IDs are never read then (edge_value looks at a neighbour's only where it is covered).
// Whether a layer covers the pixels two steps away (RING) comes from their layer counts.
#extension GL_ARB_shading_language_packing : require
layout(local_size_x = 8, local_size_y = 8) in;
#include "blueprint.render:glsl/kbuffer.glsl"
#include "blueprint.render:glsl/abuffer.glsl"

layout(r8, binding = 1) uniform writeonly image2DArray u_out;  // set by binding: moderngl cannot set image-array uniforms
layout(r32ui, binding = 2) uniform readonly uimage2D u_from;
layout(r32ui, binding = 3) uniform writeonly uimage2D u_next;
layout(r32ui, binding = 4) uniform readonly uimage2D u_layer_count;  // each pixel's layers
uniform int u_first_layer;  // the depth layer of slice 0
uniform int u_layers;  // layers of this array: slices 0 to u_layers - 1
uniform float u_back_bias;

#include "edges_held.glsl"
#define EDGE_LAST (imageSize(u_from) - 1)
// whether the current layer covers RING[r] (edges.glsl)
bool ring_covered[8];
#define EDGE_RING_COVERED(q, r) ring_covered[r]
#include "blueprint.ops:glsl/edges.glsl"

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 last = EDGE_LAST;
    if (any(greaterThan(p, last))) {
        return;
    }
    uint at[5];
    at[0] = imageLoad(u_from, p).x;
    for (int i = 0; i < 4; ++i) {
        at[i + 1] = imageLoad(u_from, clamp(p + OFFSETS[i], ivec2(0), last)).x;
    }
    for (int i = 0; i < 5; ++i) {
        sample_normal[i] = vec3(0.0);
        sample_ids[i] = ivec2(0);
    }
    // A pixel whose four neighbours have no layer left has no edge (edge_value's speck rule)
    // in any layer on, and chains only run out: most pixels of the deep arrays end here.
    int layer = 0;
    if ((at[1] | at[2] | at[3] | at[4]) != 0u) {
        uint ring[8];
        for (int r = 0; r < 8; ++r) {
            ring[r] = imageLoad(u_layer_count, clamp(p + RING[r], ivec2(0), last)).x;
        }
        for (; layer < u_layers && (at[1] | at[2] | at[3] | at[4]) != 0u; ++layer) {
            for (int i = 0; i < 5; ++i) {
                if (at[i] == 0u) {
                    sample_depth[i] = 1.0;
                    continue;
                }
                uvec4 s = AB_NODE(at[i] - 1u);
                sample_depth[i] = kb_depth(s, u_back_bias);
                sample_normal[i] = kb_normal(s);
                sample_ids[i] = kb_ids(s);
                at[i] = AB_ORDER(at[i] - 1u);
            }
            for (int r = 0; r < 8; ++r) {
                ring_covered[r] = ring[r] > uint(u_first_layer + layer);
            }
            imageStore(u_out, ivec3(p, layer), vec4(layer_edge_value(p, u_first_layer + layer)));
        }
    }
    for (; layer < u_layers; ++layer) {
        imageStore(u_out, ivec3(p, layer), vec4(0.0));
    }
    // the pixel's own chain goes on where its neighbours' ran out
    for (int k = layer; k < u_layers && at[0] != 0u; ++k) {
        at[0] = AB_ORDER(at[0] - 1u);
    }
    imageStore(u_next, p, uvec4(at[0]));
}

// The edges operation (edges.glsl) on up to BATCH depth layers at once (u_layer and the
// u_batch - 1 behind it, one target each), read straight from the surfaces a k-buffer pass
// found for them (blueprint.render:glsl/kbuffer.glsl) instead of from each layer unpacked into
// the G-buffer: one fetch a pixel and layer gives its depth, normal and IDs. The pass's count
// of the layers each pixel holds (kbuffer.frag with COUNT), read once for the batch, says
// where a layer has a surface (the targets past a pixel's last surface hold whatever an earlier
// frame left: only the first is cleared), answers for the pixels two steps away and tells
// where a pixel's lanes may stop. The samples are those the unpack would have written: the
// depth as the G-buffer's 24-bit depth holds it, 1 where the layer has no surface (its normal
// and IDs are never read then: edge_value reads a neighbour's only where it is covered).
// With COMPOSE the batch holds every layer of the frame and is composed here, into the
// composite's target, instead of written a target a layer (compose_batch.glsl).
#extension GL_ARB_shading_language_packing : require
#include "blueprint.render:glsl/kbuffer.glsl"

#ifndef SURFACE_ARRAY
#define SURFACE_ARRAY 0
#endif
#if SURFACE_ARRAY
// every layer's surfaces, slice k layer k's: one sampler, where a sampler array indexed in the
// loop below costs a software rasteriser a branch a fetch
uniform usampler2DArray u_surfaces;
#define SURFACE(k, q) texelFetch(u_surfaces, ivec3(q, u_layer + (k)), 0)
#else
uniform usampler2D u_surfaces[BATCH];  // the batch's layers, the first one's surfaces first
#define SURFACE(k, q) texelFetch(u_surfaces[k], q, 0)
#endif
uniform sampler2D u_count;
uniform int u_layer;  // the batch's first layer
uniform int u_batch;  // its layers, 1 to BATCH: outputs 0 to u_batch - 1
uniform float u_back_bias;
#ifndef COMPOSE
#define COMPOSE 0
#endif

#include "edges_held.glsl"
#define EDGE_LAST (textureSize(u_count, 0) - 1)
float ring_count[8];  // as the count's target holds it: layers / 255
float ring_held;  // counts above it hold the layer edge_value is looking at
#define EDGE_RING_COVERED(q, r) (ring_count[r] > ring_held)
#include "blueprint.ops:glsl/edges.glsl"

#if COMPOSE
// the batch composed where it is found, into the composite's target (compose_batch.glsl)
#include "blueprint.compose:glsl/compose_batch.glsl"
#else
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
#endif

// A window depth as a 24-bit depth target stores it and a shader reads it back (llvmpipe's
// rounding, checked bit for bit over the whole range)
float depth24(float z) {
    return roundEven(z * 16777215.0) * (1.0 / 16777215.0);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = EDGE_LAST;
    // the ring's counts and the neighbours' in four gathers of 2x2 blocks, not twelve fetches,
    // which cost llvmpipe more. The block whose lower left texel is p + (x0, y0),
    // gathered at its centre p + (x0 + 1, y0 + 1), comes as (x0, y0 + 1), (x0 + 1, y0 + 1),
    // (x0 + 1, y0), (x0, y0), clamped to the image as the fetches are (the pool's targets clamp
    // to edges).
    vec2 size = vec2(last + 1);
    vec4 a = textureGather(u_count, (vec2(p) + vec2(2.0, 1.0)) / size);
    vec4 b = textureGather(u_count, (vec2(p) + vec2(-1.0, 0.0)) / size);
    vec4 c = textureGather(u_count, (vec2(p) + vec2(0.0, 2.0)) / size);
    vec4 d = textureGather(u_count, (vec2(p) + vec2(1.0, -1.0)) / size);
    ring_count[0] = b.x;  // (-2, 0)
    ring_count[1] = a.z;  // (2, 0)
    ring_count[2] = d.w;  // (0, -2)
    ring_count[3] = c.y;  // (0, 2)
    ring_count[4] = b.z;  // (-1, -1)
    ring_count[5] = d.y;  // (1, -1)
    ring_count[6] = c.w;  // (-1, 1)
    ring_count[7] = a.x;  // (1, 1)
    // the layers the pixel and its neighbours (OFFSETS: (-1, 0), (1, 0), (0, -1), (0, 1)) hold;
    // the most of them: no layer behind has an edge here (edge_value's speck rule)
    float count[5] = float[5](texelFetch(u_count, p, 0).r, b.y, a.w, d.x, c.z);
    float deepest = max(max(count[0], count[1]), max(max(count[2], count[3]), count[4]));
    ivec2 q[5];
    q[0] = p;
    for (int i = 0; i < 4; ++i) {
        q[i + 1] = clamp(p + OFFSETS[i], ivec2(0), last);
    }
    float e[BATCH];
    for (int k = 0; k < BATCH; ++k) {
        e[k] = 0.0;
    }
    // the layers the pixel and its neighbours hold tested at the loop's end, where a software
    // rasteriser leaves a loop once every lane has (a break at the top runs the body once more
    // with every lane masked off); the batch's first layer is not asked: where none of them
    // holds it, edge_value finds nothing covered and gives 0
    int k = 0;
    do {
        int layer = u_layer + k;
        ring_held = (float(layer) + 0.5) / 255.0;
        for (int i = 0; i < 5; ++i) {
            uvec4 s = SURFACE(k, q[i]);
            sample_depth[i] = count[i] > ring_held ? depth24(kb_depth(s, u_back_bias)) : 1.0;
            sample_normal[i] = kb_normal(s);
            sample_ids[i] = kb_ids(s);
        }
        e[k] = layer_edge_value(p, layer);
        ++k;
    } while (k < u_batch && deepest > (float(u_layer + k) + 0.5) / 255.0);
#if COMPOSE
    o_value = compose_batch(e);
#else
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
#endif
}

// The edges operation (edges.glsl) on one layer read straight from the surface a k-buffer pass
// found for it (blueprint.render:glsl/kbuffer.glsl) instead of from the layer unpacked into the
// G-buffer: one fetch a pixel gives its depth, normal and IDs, or nothing where the layer has
// no surface (every surface was cleared before the pass); the pass's count of the layers each
// pixel holds (kbuffer.frag with COUNT) answers for the pixels two steps away. The samples are those
// the unpack would have written: the depth as the G-buffer's 24-bit depth holds it, 1 where the
// layer has no surface.
#extension GL_ARB_shading_language_packing : require
#extension GL_ARB_texture_gather : require
#include "blueprint.render:glsl/kbuffer.glsl"

uniform usampler2D u_surfaces;
uniform sampler2D u_count;
uniform float u_held;  // (layer + 0.5) / 255: counts above it hold the layer
uniform float u_back_bias;
uniform int u_layer;

#include "edges_held.glsl"
#define EDGE_LAST (textureSize(u_count, 0) - 1)
bool ring_covered[8];
#define EDGE_RING_COVERED(q, r) ring_covered[r]
#include "blueprint.ops:glsl/edges.glsl"

out vec4 o_edge;

// A window depth as a 24-bit depth target stores it and a shader reads it back (llvmpipe's
// rounding, checked bit for bit over the whole range)
float depth24(float z) {
    return roundEven(z * 16777215.0) * (1.0 / 16777215.0);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = EDGE_LAST;
    for (int i = 0; i < 5; ++i) {
        ivec2 q = i == 0 ? p : clamp(p + OFFSETS[i - 1], ivec2(0), last);
        uvec4 s = texelFetch(u_surfaces, q, 0);
        sample_depth[i] = kb_empty(s) ? 1.0 : depth24(kb_depth(s, u_back_bias));
        sample_normal[i] = kb_normal(s);
        sample_ids[i] = kb_ids(s);
    }
    // the ring's counts in four gathers of two ring pixels each, not eight fetches (7 % of the
    // edges' time on llvmpipe). The 2x2 block whose lower left texel is p + (x0, y0), gathered
    // at its centre p + (x0 + 1, y0 + 1), comes as (x0, y0 + 1), (x0 + 1, y0 + 1), (x0 + 1, y0),
    // (x0, y0), clamped to the image as the fetches above (the pool's targets clamp to edges).
    vec2 size = vec2(last + 1);
    bvec4 a = greaterThan(textureGather(u_count, (vec2(p) + vec2(2.0, 1.0)) / size), vec4(u_held));
    bvec4 b = greaterThan(textureGather(u_count, (vec2(p) + vec2(-1.0, 0.0)) / size), vec4(u_held));
    bvec4 c = greaterThan(textureGather(u_count, (vec2(p) + vec2(0.0, 2.0)) / size), vec4(u_held));
    bvec4 d = greaterThan(textureGather(u_count, (vec2(p) + vec2(1.0, -1.0)) / size), vec4(u_held));
    ring_covered[0] = b.x;  // (-2, 0)
    ring_covered[1] = a.z;  // (2, 0)
    ring_covered[2] = d.w;  // (0, -2)
    ring_covered[3] = c.y;  // (0, 2)
    ring_covered[4] = b.z;  // (-1, -1)
    ring_covered[5] = d.y;  // (1, -1)
    ring_covered[6] = c.w;  // (-1, 1)
    ring_covered[7] = a.x;  // (1, 1)
    o_edge = vec4(layer_edge_value(p, u_layer));
}

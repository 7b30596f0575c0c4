// The edges operation (edges.glsl) on one layer read straight from the surface a k-buffer pass
// found for it (blueprint.render:glsl/kbuffer.glsl) instead of from the layer unpacked into the
// G-buffer: one fetch a pixel gives its depth, normal and IDs, or nothing where the layer has
// no surface (every surface was cleared before the pass); the pass's count of the layers each
// pixel holds (kbuffer.frag with COUNT) answers for the pixels two steps away. The samples are those
// the unpack would have written: the depth as the G-buffer's 24-bit depth holds it, 1 where the
// layer has no surface.
#extension GL_ARB_shading_language_packing : require
#include "blueprint.render:glsl/kbuffer.glsl"

uniform usampler2D u_surfaces;
uniform sampler2D u_count;
uniform float u_held;  // (layer + 0.5) / 255: counts above it hold the layer
uniform float u_back_bias;
uniform int u_layer;

// the pixel (0) and its neighbours OFFSETS[i] (i + 1)
float sample_depth[5];
vec3 sample_normal[5];
ivec2 sample_ids[5];
#define EDGE_SAMPLES 1
#define EDGE_LAST (textureSize(u_count, 0) - 1)
#define EDGE_DEPTH(q, i) sample_depth[(i) + 1]
#define EDGE_NORMAL(q, i) sample_normal[(i) + 1]
#define EDGE_IDS(q, i) sample_ids[(i) + 1]
#define EDGE_RING_COVERED(q, r) (texelFetch(u_count, q, 0).r > u_held)
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
    o_edge = vec4(layer_edge_value(p, u_layer));
}

// One layer of the A-buffer into the G-buffer, as the peel would have drawn it: at each pixel
// the surface at its cursor (which then moves on to the pixel's next layer), its depth whole
// (see abuffer_resolve.comp); depth 1 where the pixel has no more layers, normal and IDs then
// left as they are (as a peel pass leaves them).
#extension GL_ARB_shading_language_packing : require
layout(local_size_x = 8, local_size_y = 8) in;
#include "kbuffer.glsl"
#include "abuffer.glsl"

layout(binding = 1, r32ui) coherent uniform uimage2D u_cursor;
layout(binding = 2, r32f) writeonly uniform image2D u_depth;
layout(binding = 3, rgba16f) writeonly uniform image2D u_normal;
layout(binding = 4, rg32i) writeonly uniform iimage2D u_ids;
uniform float u_back_bias;
#if TILES
// Only the tiles with a pixel this deep, most layers first (the rest of the depth target is
// cleared to 1)
#define TILE_LIST_BINDING 0
#include "abuffer_tiles.glsl"

ivec2 pixel() {
    return listed_pixel();
}
#else
ivec2 pixel() {
    return ivec2(gl_GlobalInvocationID.xy);
}
#endif

void main() {
    ivec2 p = pixel();
    if (p.x < 0) {
        return;
    }
    if (any(greaterThanEqual(p, imageSize(u_cursor)))) {
        return;
    }
    uint at = imageLoad(u_cursor, p).x;
    if (at == 0u) {
        imageStore(u_depth, p, vec4(1.0));
        return;
    }
    uvec4 s = AB_NODE(at - 1u);
    imageStore(u_cursor, p, uvec4(AB_ORDER(at - 1u)));
    imageStore(u_depth, p, vec4(kb_depth(s, u_back_bias)));
    imageStore(u_normal, p, vec4(kb_normal(s), 1.0));
    imageStore(u_ids, p, ivec4(kb_ids(s), 0, 0));
}

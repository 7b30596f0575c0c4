// The faces that can cover a pixel the occlusion pass reads for a drawing's contour samples
// (vector/contour_gpu.py): the faces k-buffer of the lines' levels draws those alone, in their
// order. STAGE 0: bit f % 32 of word f / 32 set where face f's box on screen (contours.comp's
// bounds) meets a tile of u_mask, or spans more than MOST_TILES tiles (kept unread). STAGE 1:
// the kept faces' corners, in order, into an index buffer of their own.
layout(local_size_x = 64) in;

#if STAGE == 0
#define MOST_TILES 16
layout(std430, binding = 11) readonly buffer Bounds { uint bounds[]; };
layout(std430, binding = 12) writeonly buffer Kept { uint kept_bits[]; };
uniform usampler2D u_mask;  // 1 where a tile holds a pixel the occlusion pass reads
uniform int u_faces;

shared uint s_kept[2];

bool near(uint box) {
    if (box == 0xffffffffu) {
        return true;  // a corner behind the eye
    }
    uvec2 first = uvec2(box & 0xffu, (box >> 8) & 0xffu);
    uvec2 last = uvec2((box >> 16) & 0xffu, box >> 24);
    if (any(greaterThan(first, last))) {
        return false;
    }
    uvec2 span = last - first + 1u;
    if (span.x * span.y > uint(MOST_TILES)) {
        return true;
    }
    bool hit = false;
    for (uint y = first.y; y <= last.y; ++y) {
        for (uint x = first.x; x <= last.x; ++x) {
            hit = hit || texelFetch(u_mask, ivec2(x, y), 0).r != 0u;
        }
    }
    return hit;
}

void main() {
    uint local = gl_LocalInvocationID.x;
    if (local < 2u) {
        s_kept[local] = 0u;
    }
    barrier();
    int f = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (f < u_faces && near(bounds[f])) {
        atomicOr(s_kept[local >> 5], 1u << (local & 31u));
    }
    barrier();
    if (local < 2u) {
        uint word = (gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x) * 2u + local;
        if (int(word * 32u) < u_faces) {
            kept_bits[word] = s_kept[local];
        }
    }
}
#else
#include "table.glsl"

layout(std430, binding = 6) readonly buffer Indices { uint indices[]; };
layout(std430, binding = 13) writeonly buffer Subset { uint subset[]; };
uniform isampler2D u_kept;  // a table (gpu/tables.py) of the kept faces, ascending
uniform int u_count;

void main() {
    int i = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (i >= u_count) {
        return;
    }
    uint f = uint(TABLE_ROW(u_kept, i).r);
    subset[3 * i] = indices[3u * f];
    subset[3 * i + 1] = indices[3u * f + 1u];
    subset[3 * i + 2] = indices[3u * f + 2u];
}
#endif

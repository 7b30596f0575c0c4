// The broad phase of the intersection lines (vector/lines.py, the reference): one invocation
// per busy entry of the grid (lines.cell_grid) walks its partners in the cell as
// lines._candidate_pairs does, and hands on the pairs whose single-precision boxes (rounded
// outwards) overlap and whose first common cell is this one (as entry indices) to
// triangle_cuts.comp, which tests the exact boxes first. The exact test stays out of this
// loop: llvmpipe runs a branch's body for a SIMD vector whether or not any lane takes it, so
// every partner would pay for six texel fetches and the doubles' comparisons.
#include "table.glsl"

layout(local_size_x = 64) in;

// tables (gpu/tables.py): the first cell of each box; the box of every entry; two rows per
// triangle: its box in single precision, rounded outwards (low, high + slack)
uniform isampler2D u_firsts;
uniform isampler2D u_owners;
uniform sampler2D u_boxes;
// busy entries: entry index, end of its part's run in the cell, end of the cell; the cell
layout(std430, binding = 3) readonly buffer Entries { ivec4 entries[]; };
layout(std430, binding = 4) readonly buffer Cells { ivec4 cells[]; };
layout(std430, binding = 6) buffer Pairs { uint pair_count; uint pair_pad; uvec2 pairs[]; };

uniform int u_count;     // busy entries
uniform int u_capacity;  // pairs the pairs buffer holds

void main() {
    int e = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (e >= u_count) return;
    ivec4 entry = entries[e];
    ivec3 cell = cells[e].xyz;
    int i = TABLE_ROW(u_owners, entry.x).x;
    ivec3 first_a = TABLE_ROW(u_firsts, i).xyz;
    vec3 rough_lo = TABLE_ROW(u_boxes, 2 * i).xyz, rough_hi = TABLE_ROW(u_boxes, 2 * i + 1).xyz;
    for (int ib = entry.y; ib < entry.z; ++ib) {
        int j = TABLE_ROW(u_owners, ib).x;
        // most partners' boxes miss by far: tell those from single-precision boxes
        if (any(greaterThan(rough_lo, TABLE_ROW(u_boxes, 2 * j + 1).xyz))) continue;
        if (any(greaterThan(TABLE_ROW(u_boxes, 2 * j).xyz, rough_hi))) continue;
        if (max(first_a, TABLE_ROW(u_firsts, j).xyz) != cell) continue;
        uint slot = atomicAdd(pair_count, 1u);
        if (slot < uint(u_capacity)) pairs[slot] = uvec2(entry.x, ib);
    }
}

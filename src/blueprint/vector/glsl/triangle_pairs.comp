// The broad phase of the intersection lines (vector/lines.py, the reference): one invocation
// per busy entry of the grid (lines.cell_grid) walks its partners in the cell as
// lines._candidate_pairs does, and hands on the pairs whose boxes overlap and whose first
// common cell is this one (as entry indices) to triangle_cuts.comp.
#include "triangles.glsl"

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
    dvec4 a0 = tri_row(4 * i), a1 = tri_row(4 * i + 1), a2 = tri_row(4 * i + 2);
    dvec3 lo_a = min(min(a0.xyz, a1.xyz), a2.xyz);
    dvec3 hi_a = dvec3(a0.w, a1.w, a2.w);
    ivec3 first_a = TABLE_ROW(u_firsts, i).xyz;
    vec3 rough_lo = TABLE_ROW(u_boxes, 2 * i).xyz, rough_hi = TABLE_ROW(u_boxes, 2 * i + 1).xyz;
    for (int ib = entry.y; ib < entry.z; ++ib) {
        int j = TABLE_ROW(u_owners, ib).x;
        // most partners' boxes miss by far: tell those from single-precision boxes
        if (any(greaterThan(rough_lo, TABLE_ROW(u_boxes, 2 * j + 1).xyz))) continue;
        if (any(greaterThan(TABLE_ROW(u_boxes, 2 * j).xyz, rough_hi))) continue;
        dvec4 b0 = tri_row(4 * j), b1 = tri_row(4 * j + 1), b2 = tri_row(4 * j + 2);
        dvec3 lo_b = min(min(b0.xyz, b1.xyz), b2.xyz);
        dvec3 hi_b = dvec3(b0.w, b1.w, b2.w);
        if (any(greaterThan(lo_a, hi_b)) || any(greaterThan(lo_b, hi_a))) continue;
        if (max(first_a, TABLE_ROW(u_firsts, j).xyz) != cell) continue;
        uint slot = atomicAdd(pair_count, 1u);
        if (slot < uint(u_capacity)) pairs[slot] = uvec2(entry.x, ib);
    }
}

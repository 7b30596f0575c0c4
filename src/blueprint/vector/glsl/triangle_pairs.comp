// The broad phase of the intersection lines (vector/lines.py, the reference): one invocation
// per busy entry of the grid (lines.cell_grid) walks its partners in the cell as
// lines._candidate_pairs does, and hands on the pairs whose boxes overlap and whose first
// common cell is this one (as entry indices) to triangle_cuts.comp.
layout(local_size_x = 64) in;

// four per triangle: its corners (w: its box's high corner, slack added, x then y then z) and
// its unit normal (w: 1 where it has one)
layout(std430, binding = 0) readonly buffer Triangles { dvec4 tris[]; };
layout(std430, binding = 1) readonly buffer Firsts { ivec4 firsts[]; };  // first cell of each box
layout(std430, binding = 2) readonly buffer Owners { int owners[]; };    // box of every entry
// busy entries: entry index, end of its part's run in the cell, end of the cell; the cell
layout(std430, binding = 3) readonly buffer Entries { ivec4 entries[]; };
layout(std430, binding = 4) readonly buffer Cells { ivec4 cells[]; };
// two per triangle: its box in single precision, rounded outwards (low, high + slack)
layout(std430, binding = 5) readonly buffer Boxes { vec4 boxes[]; };
layout(std430, binding = 6) buffer Pairs { uint pair_count; uint pair_pad; uvec2 pairs[]; };

uniform int u_count;     // busy entries
uniform int u_capacity;  // pairs the pairs buffer holds

void main() {
    int e = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (e >= u_count) return;
    ivec4 entry = entries[e];
    ivec3 cell = cells[e].xyz;
    int i = owners[entry.x];
    dvec4 a0 = tris[4 * i], a1 = tris[4 * i + 1], a2 = tris[4 * i + 2];
    dvec3 lo_a = min(min(a0.xyz, a1.xyz), a2.xyz);
    dvec3 hi_a = dvec3(a0.w, a1.w, a2.w);
    ivec3 first_a = firsts[i].xyz;
    vec3 rough_lo = boxes[2 * i].xyz, rough_hi = boxes[2 * i + 1].xyz;
    for (int ib = entry.y; ib < entry.z; ++ib) {
        int j = owners[ib];
        // most partners' boxes miss by far: tell those from single-precision boxes
        if (any(greaterThan(rough_lo, boxes[2 * j + 1].xyz)) || any(greaterThan(boxes[2 * j].xyz, rough_hi))) continue;
        dvec4 b0 = tris[4 * j], b1 = tris[4 * j + 1], b2 = tris[4 * j + 2];
        dvec3 lo_b = min(min(b0.xyz, b1.xyz), b2.xyz);
        dvec3 hi_b = dvec3(b0.w, b1.w, b2.w);
        if (any(greaterThan(lo_a, hi_b)) || any(greaterThan(lo_b, hi_a))) continue;
        if (max(first_a, firsts[j].xyz) != cell) continue;
        uint slot = atomicAdd(pair_count, 1u);
        if (slot < uint(u_capacity)) pairs[slot] = uvec2(entry.x, ib);
    }
}

// The triangles of the intersection passes (cuts.py), a table (gpu/tables.py) of their float64
// rows' bits, two doubles a texel: four rows per triangle, its corners (w: its box's high
// corner, slack added, x then y then z) and its unit normal (w: 1 where it has one).
#include "table.glsl"

uniform usampler2D u_tris;

dvec4 tri_row(int r) {
    uvec4 lo = TABLE_ROW(u_tris, 2 * r), hi = TABLE_ROW(u_tris, 2 * r + 1);
    return dvec4(packDouble2x32(lo.xy), packDouble2x32(lo.zw), packDouble2x32(hi.xy), packDouble2x32(hi.zw));
}

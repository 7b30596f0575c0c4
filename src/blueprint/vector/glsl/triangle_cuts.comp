// The narrow phase of the intersection lines (vector/lines.py, the reference): one invocation
// per pair of triangle_pairs.comp keeps it where the triangles' exact boxes overlap (as
// lines._candidate_pairs tests them) and, tested as lines._triangle_pairs_cut does in double
// precision, the triangles may cut through each other. The test is
// conservative: every threshold is loosened by u_tol (distances to a plane) or u_tol_span
// (lengths along the cut), far above the rounding that separates this arithmetic from
// NumPy's, and a pair with a corner that close to a plane's touch tolerance is kept untested;
// the caller cuts the pairs kept with NumPy, so the lines are NumPy's.
#include "triangles.glsl"

layout(local_size_x = 64) in;

uniform isampler2D u_owners;  // a table (gpu/tables.py): the box of every entry
layout(std430, binding = 6) readonly buffer Pairs { uint pair_count; uint pair_pad; uvec2 pairs[]; };
layout(std430, binding = 7) buffer Found { uint found_count; uint found_pad; uvec2 found[]; };

uniform int u_count;     // pairs
uniform int u_capacity;  // pairs the found buffer holds
uniform double u_eps;    // the touch tolerance: corners this near a plane lie on it
uniform double u_tol;
uniform double u_tol_span;

// the two points where a triangle meets a plane, its corners' distances d zeroed within eps:
// the first two of its edges crossing and corners touching, in lines._plane_cut's order
void plane_cut(dvec3 t[3], dvec3 d, out dvec3 p0, out dvec3 p1) {
    dvec3 cand[6];
    bool valid[6];
    for (int a = 0; a < 3; ++a) {
        int b = (a + 1) % 3;
        valid[a] = d[a] * d[b] < 0.0LF;
        double u = valid[a] ? d[a] / (d[a] - d[b]) : 0.0LF;
        cand[a] = t[a] + u * (t[b] - t[a]);
        valid[3 + a] = d[a] == 0.0LF;
        cand[3 + a] = t[a];
    }
    p0 = p1 = dvec3(0.0LF);
    int got = 0;
    for (int k = 0; k < 6; ++k) {
        if (valid[k]) {
            if (got == 0) p0 = cand[k];
            else if (got == 1) p1 = cand[k];
            ++got;
        }
    }
}

// a corner on each side of the plane, beyond eps: NumPy's "proper", loosened
bool maybe_proper(dvec3 d) {
    double lim = u_eps - u_tol;
    return (d.x > lim || d.y > lim || d.z > lim) && (d.x < -lim || d.y < -lim || d.z < -lim);
}

// a corner whose distance is within tol of eps: NumPy may zero it or not
bool unsure(dvec3 d) {
    dvec3 off = abs(abs(d) - dvec3(u_eps));
    return off.x <= u_tol || off.y <= u_tol || off.z <= u_tol;
}

dvec3 zeroed(dvec3 d) {
    return mix(d, dvec3(0.0LF), lessThanEqual(abs(d), dvec3(u_eps)));
}

bool may_cut(dvec3 ta[3], dvec4 na, dvec3 tb[3], dvec4 nb) {
    if (nb.w == 0.0LF || na.w == 0.0LF) return false;
    dvec3 da = dvec3(dot(ta[0] - tb[0], nb.xyz), dot(ta[1] - tb[0], nb.xyz), dot(ta[2] - tb[0], nb.xyz));
    if (!maybe_proper(da)) return false;
    dvec3 db = dvec3(dot(tb[0] - ta[0], na.xyz), dot(tb[1] - ta[0], na.xyz), dot(tb[2] - ta[0], na.xyz));
    if (!maybe_proper(db)) return false;
    if (unsure(da) || unsure(db)) return true;
    dvec3 a0, a1, b0, b1;
    plane_cut(ta, zeroed(da), a0, a1);
    plane_cut(tb, zeroed(db), b0, b1);
    dvec3 direction = cross(na.xyz, nb.xyz);
    double sa0 = dot(a0, direction), sa1 = dot(a1, direction);
    double sb0 = dot(b0, direction), sb1 = dot(b1, direction);
    double lo = max(min(sa0, sa1), min(sb0, sb1));
    double hi = min(max(sa0, sa1), max(sb0, sb1));
    double dlen = length(direction);
    return hi - lo > u_eps * max(dlen, 1e-300LF) - u_tol_span * (dlen + 1.0LF);
}

void main() {
    int p = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (p >= u_count) return;
    uvec2 pair = pairs[p];
    int i = TABLE_ROW(u_owners, int(pair.x)).x, j = TABLE_ROW(u_owners, int(pair.y)).x;
    dvec4 a0 = tri_row(4 * i), a1 = tri_row(4 * i + 1), a2 = tri_row(4 * i + 2);
    dvec4 b0 = tri_row(4 * j), b1 = tri_row(4 * j + 1), b2 = tri_row(4 * j + 2);
    // w: the box's high corner, slack added
    if (any(greaterThan(min(min(a0.xyz, a1.xyz), a2.xyz), dvec3(b0.w, b1.w, b2.w)))) return;
    if (any(greaterThan(min(min(b0.xyz, b1.xyz), b2.xyz), dvec3(a0.w, a1.w, a2.w)))) return;
    dvec3 ta[3] = dvec3[3](a0.xyz, a1.xyz, a2.xyz);
    dvec3 tb[3] = dvec3[3](b0.xyz, b1.xyz, b2.xyz);
    if (!may_cut(ta, tri_row(4 * i + 3), tb, tri_row(4 * j + 3))) return;
    uint slot = atomicAdd(found_count, 1u);
    if (slot < uint(u_capacity)) found[slot] = pair;
}

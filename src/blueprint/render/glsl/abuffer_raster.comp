// The A-buffer's geometry pass (abuffer.frag) done in compute (render/raster.py): triangles snapped to 1/256 pixel as a rasteriser snaps them, binned to tiles of TILE x TILE
// pixels, and each tile's pixels tested against its triangles by one workgroup, every covered
// pixel centre's fragment appended to the pixel's list as the fragment shader appends it.
// STAGE 0 sets each triangle up and counts the tiles it touches, 1 turns the counts into
// where each tile's triangles start, 2 lists the triangles of each tile, 3 rasterises. The
// four run over a chunk of the mesh's faces at a time (from u_first, u_triangles of them),
// each appending to the lists the chunks before it left: the set-up and bins hold one chunk.
// A triangle's edges are kept as equations exact in double precision (corners are integers
// below 2^21, so every term is an integer below 2^53), the top-left rule folded in: a tile is
// binned only where some pixel centre of it lies inside all three edges' half-planes (thin
// triangles across a model bin to a fraction of the tiles of their bounds), and a pixel's test
// is three multiply-adds against the equations moved to its tile.
#extension GL_ARB_shading_language_packing : require
#include "blueprint.render:glsl/kbuffer.glsl"
#include "blueprint.render:glsl/abuffer.glsl"
#include "instance.glsl"

#define TILE 16
#define SNAP 256.0
#if STAGE == 1
#define GROUP 1024
layout(local_size_x = GROUP) in;
#elif STAGE == 3
layout(local_size_x = TILE, local_size_y = TILE) in;
#else
layout(local_size_x = 64) in;
#endif

// the mesh's interleaved vertices (position, normal, part as int bits) and faces, in their
// meshes' own coordinates: triangle t of the chunk is face ID u_first + t, placed by its
// instance (instance.glsl's faces table)
layout(std430, binding = 5) readonly buffer Vertices { float vertices[]; };
layout(std430, binding = 6) readonly buffer Indices { uint indices[]; };
// a triangle's setup, five ivec4: snapped corners (x0, y0, x1, y1), (x2, y2, z0, z1), (z2,
// 1/w0, 1/w1, 1/w2) as float bits, its tiles (first x | y << 16, last x | y << 16; 0 where it
// draws nothing) and the third corner unsnapped, the first two unsnapped: depth and the
// attributes follow the plane through the corners as projected (the rasteriser's coverage
// follows the snapped ones)
layout(std430, binding = 11) buffer Setup { ivec4 setup[]; };
layout(std430, binding = 12) buffer TileCount { uint tile_count[]; };
layout(std430, binding = 13) buffer TileStart { uint tile_start[]; };
layout(std430, binding = 14) buffer Bins { uint bins[]; };
// a triangle's three edge equations E(x, y) = a x + b y + c over positions in 1/256 pixel,
// front-facing order, >= 0 inside (a pixel centre on an edge it does not own is outside)
layout(std430, binding = 15) buffer Edges { double edge_eq[]; };
layout(binding = 0, r32ui) coherent uniform uimage2D u_head;

uniform mat4 u_view;
uniform mat4 u_projection;
uniform bool u_ortho;
uniform ivec2 u_size;
uniform int u_first;
uniform int u_triangles;
uniform int u_tile_columns;
uniform int u_tiles;
uniform int u_bin_room;

vec3 position(uint v) { return vec3(vertices[7u * v], vertices[7u * v + 1u], vertices[7u * v + 2u]); }
vec3 normal(uint v) { return vec3(vertices[7u * v + 3u], vertices[7u * v + 4u], vertices[7u * v + 5u]); }

#if STAGE == 0 || STAGE == 2
// this invocation's index over a two-dimensional dispatch: a dimension holds at most 65535
// workgroups, fewer than a big model's triangles need
int invocation() {
    return int(gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64 + int(gl_LocalInvocationID.x);
}

// the tiles' corners of triangle t, or false where it covers no pixel centre
bool tiles_of(int t, out ivec2 first, out ivec2 last) {
    ivec4 s = setup[5 * t + 3];
    if (s.x == 0 && s.y == 0) {
        return false;
    }
    first = ivec2(s.x & 0xffff, s.x >> 16);
    last = ivec2(s.y & 0xffff, s.y >> 16);
    return true;
}
#endif

#if STAGE == 0 || STAGE == 2
// the tiles of row y, within bounds (first, last), that snapped corners c may reach: the x
// extent of the triangle cut to the row's band of pixel centres (a sliver across the model
// walks its own tiles, not its bounds')
ivec2 row_tiles(ivec2 c[3], int y, ivec2 bounds) {
    double ya = double(y * TILE * 256 + 128), yb = ya + double((TILE - 1) * 256);
    double lo = 1e30, hi = -1e30;
    for (int i = 0; i < 3; ++i) {
        dvec2 p = dvec2(c[i]), q = dvec2(c[(i + 1) % 3]);
        if (p.y >= ya && p.y <= yb) {
            lo = min(lo, p.x);
            hi = max(hi, p.x);
        }
        for (int side = 0; side < 2; ++side) {
            double at = side == 0 ? ya : yb;
            if ((p.y - at) * (q.y - at) < 0.0) {
                double x = p.x + (q.x - p.x) * (at - p.y) / (q.y - p.y);
                lo = min(lo, x);
                hi = max(hi, x);
            }
        }
    }
    // (a unit wider each way: the division rounds)
    int span = TILE * 256;
    return ivec2(max(bounds.x, int(floor((lo - 1.0) / double(span)))), min(bounds.y, int(floor((hi + 1.0) / double(span)))));
}

// whether any pixel centre of tile (x, y) lies inside all three edges (a, b, c: one edge's
// equation a component)
bool touches(dvec3 a, dvec3 b, dvec3 c, int x, int y) {
    // the tile's first and last pixel centres, in 1/256 pixel
    dvec2 lo = dvec2(ivec2(x, y) * (TILE * 256) + 128);
    double span = double((TILE - 1) * 256);
    dvec3 most = a * lo.x + b * lo.y + c + max(a * span, 0.0) + max(b * span, 0.0);
    return all(greaterThanEqual(most, dvec3(0.0)));
}

// Stages 0 and 2 walk a triangle's tiles in ROWS threads, each taking every ROWS-th row of
// tiles: a big triangle's walk otherwise held up its whole subgroup.
#define ROWS 8
#endif

#if STAGE == 0
// the pixel centre on the edge from a to b belongs to the triangle on the edge's left or top
// side only, so that two triangles sharing the edge do not both draw it
bool owns(ivec2 a, ivec2 b) {
    ivec2 d = b - a;
    return d.y < 0 || (d.y == 0 && d.x < 0);
}

// (a, b, c) of the edge from corner p to q: twice the signed area of (p, q, position)
void put_edge(int i, ivec2 p, ivec2 q, inout dvec3 a, inout dvec3 b, inout dvec3 c) {
    a[i] = -double(q.y - p.y);
    b[i] = double(q.x - p.x);
    double at = double(q.y - p.y) * double(p.x) - double(q.x - p.x) * double(p.y);
    // values are integers: "> 0, or 0 where the edge is owned" is ">= 0" after this
    c[i] = owns(p, q) ? at : at - 1.0;
}

void main() {
    int t = invocation() / ROWS, row = invocation() % ROWS;
    if (t >= u_triangles) {
        return;
    }
    ivec2 corner[3];
    vec2 exact[3];
    float z[3], inv_w[3];
    bool behind = false;
    int placed = placement_of(u_first + t);
    uint face = placed_face(placed, u_first + t);
    for (int k = 0; k < 3; ++k) {
        vec4 clip = u_projection * (u_view * vec4(placed_point(placed, position(indices[3u * face + uint(k)])), 1.0));
        behind = behind || clip.w <= 0.0;
        vec3 ndc = clip.xyz / clip.w;
        vec2 window = (ndc.xy * 0.5 + 0.5) * vec2(u_size);
        exact[k] = window;
        corner[k] = ivec2(round(window * SNAP));
        z[k] = ndc.z * 0.5 + 0.5;
        inv_w[k] = 1.0 / clip.w;
    }
    ivec2 lo = min(corner[0], min(corner[1], corner[2]));
    ivec2 hi = max(corner[0], max(corner[1], corner[2]));
    // pixel centres inside the bounds: 256 p + 128 in [lo, hi]
    ivec2 first = max((lo - 128 + 255) >> 8, ivec2(0));
    ivec2 last = min((hi - 128) >> 8, u_size - 1);
    double area = double(corner[1].x - corner[0].x) * double(corner[2].y - corner[0].y)
        - double(corner[2].x - corner[0].x) * double(corner[1].y - corner[0].y);
    bool first_row = row == 0;
    if (first_row) {
        setup[5 * t] = ivec4(corner[0], corner[1]);
        setup[5 * t + 1] = ivec4(corner[2], floatBitsToInt(z[0]), floatBitsToInt(z[1]));
        setup[5 * t + 2] = ivec4(floatBitsToInt(z[2]), floatBitsToInt(inv_w[0]), floatBitsToInt(inv_w[1]),
            floatBitsToInt(inv_w[2]));
    }
    // (no vertex lies behind the eye: such views are left to the graphics pipeline, which
    // clips; render.raster.ComputeRaster.sees)
    if (behind || area == 0.0 || any(greaterThan(first, last))) {
        if (first_row) {
            setup[5 * t + 3] = ivec4(0);
        }
        return;
    }
    ivec2 tile0 = first / TILE, tile1 = last / TILE;
    ivec2 c0 = corner[0], c1 = corner[1], c2 = corner[2];
    if (area < 0.0) {
        c1 = corner[2];
        c2 = corner[1];
    }
    dvec3 a, b, c;
    put_edge(0, c1, c2, a, b, c);
    put_edge(1, c2, c0, a, b, c);
    put_edge(2, c0, c1, a, b, c);
    if (first_row) {
        setup[5 * t + 3] = ivec4(tile0.x | (tile0.y << 16), tile1.x | (tile1.y << 16), floatBitsToInt(exact[2]));
        setup[5 * t + 4] = ivec4(floatBitsToInt(exact[0]), floatBitsToInt(exact[1]));
        for (int i = 0; i < 3; ++i) {
            edge_eq[9 * t + 3 * i] = a[i];
            edge_eq[9 * t + 3 * i + 1] = b[i];
            edge_eq[9 * t + 3 * i + 2] = c[i];
        }
    }
    for (int y = tile0.y + row; y <= tile1.y; y += ROWS) {
        ivec2 xs = row_tiles(corner, y, ivec2(tile0.x, tile1.x));
        for (int x = xs.x; x <= xs.y; ++x) {
            if (touches(a, b, c, x, y)) {
                atomicAdd(tile_count[y * u_tile_columns + x], 1u);
            }
        }
    }
}
#elif STAGE == 1
shared uint sums[GROUP];
void main() {
    uint i = gl_LocalInvocationID.x;
    uint chunk = (uint(u_tiles) + GROUP - 1u) / GROUP;
    uint begin = min(i * chunk, uint(u_tiles)), end = min(begin + chunk, uint(u_tiles));
    uint total = 0u;
    for (uint k = begin; k < end; ++k) {
        total += tile_count[k];
    }
    sums[i] = total;
    barrier();
    for (uint step = 1u; step < GROUP; step <<= 1) {
        uint add = i >= step ? sums[i - step] : 0u;
        barrier();
        sums[i] += add;
        barrier();
    }
    uint at = sums[i] - total;
    for (uint k = begin; k < end; ++k) {
        tile_start[k] = at;
        at += tile_count[k];
        tile_count[k] = 0u;
    }
    if (i == GROUP - 1u) {
        tile_start[u_tiles] = sums[i];
        // more than the bins hold: the capture sees it (the most of any chunk) and draws again
        // with room for them
        atomicMax(pairs, sums[i]);
    }
}
#elif STAGE == 2
void main() {
    int t = invocation() / ROWS, row = invocation() % ROWS;
    ivec2 first, last;
    if (t >= u_triangles || !tiles_of(t, first, last)) {
        return;
    }
    ivec4 s0 = setup[5 * t], s1 = setup[5 * t + 1];
    ivec2 corner[3] = ivec2[3](s0.xy, s0.zw, s1.xy);
    dvec3 a = dvec3(edge_eq[9 * t], edge_eq[9 * t + 3], edge_eq[9 * t + 6]);
    dvec3 b = dvec3(edge_eq[9 * t + 1], edge_eq[9 * t + 4], edge_eq[9 * t + 7]);
    dvec3 c = dvec3(edge_eq[9 * t + 2], edge_eq[9 * t + 5], edge_eq[9 * t + 8]);
    for (int y = first.y + row; y <= last.y; y += ROWS) {
        ivec2 xs = row_tiles(corner, y, ivec2(first.x, last.x));
        for (int x = xs.x; x <= xs.y; ++x) {
            if (!touches(a, b, c, x, y)) {
                continue;
            }
            uint tile = uint(y * u_tile_columns + x);
            uint at = tile_start[tile] + atomicAdd(tile_count[tile], 1u);
            if (at < uint(u_bin_room)) {
                bins[at] = uint(t);
            }
        }
    }
}
#else
// triangles a batch: shared memory holds their set-up (32K at most on some drivers)
#define BATCH 128
// each held triangle's corners' depths, its corners as projected (unsnapped), its place in the
// chunk, facing, and edge equations moved to the tile: E at its first pixel centre and E's steps a
// pixel along x and y
shared vec3 held_z[BATCH];
shared vec4 held_p01[BATCH];
shared vec2 held_p2[BATCH];
shared int held_t[BATCH];
#if !SLIM
shared int held_placement[BATCH];
#endif
shared bool held_front[BATCH];
shared dvec3 held_at[BATCH];
shared dvec3 held_dx[BATCH];
shared dvec3 held_dy[BATCH];

// the depth of held triangle k at the pixel centre (the plane through the corners as
// projected), with its barycentrics; false where it lies outside the depth range
bool depth_at(uint k, ivec2 pixel, out float z, out vec3 b) {
    vec2 p0 = held_p01[k].xy, p1 = held_p01[k].zw, p2 = held_p2[k];
    vec2 d10 = p1 - p0, d20 = p2 - p0, at = vec2(pixel) + 0.5 - p0;
    float twice = d10.x * d20.y - d20.x * d10.y;
    b.y = (at.x * d20.y - d20.x * at.y) / twice;
    b.z = (d10.x * at.y - at.x * d10.y) / twice;
    b.x = 1.0 - b.y - b.z;
    vec3 zs = held_z[k];
    z = zs.x + b.y * (zs.y - zs.x) + b.z * (zs.z - zs.x);
    return z >= 0.0 && z <= 1.0;
}

// each held triangle's fragments in the tile, then where the next of them goes in the batch's
// nodes (triangle k's fragments side by side: passes that read a pixel's layer and its
// neighbours' read the same triangle's nodes where they lie together, as the fragment shader's
// appends leave them)
shared uint tri_count[BATCH];
shared uint tri_next[BATCH];
shared uint group_base;

// The workgroup owns its tile's pixels: each pixel's list head stays in a register and is
// stored once, and the fragments of a batch of triangles take their nodes with one atomic on
// the fragment counter for the whole group (counted first, then written), where the fragment
// shader spends an atomic on the counter and one on the head a fragment. The count keeps the
// batch's triangles that cover the pixel as bits, so the write tests no triangle again.
void main() {
    uint tile = gl_WorkGroupID.y * uint(u_tile_columns) + gl_WorkGroupID.x;
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    bool inside = all(lessThan(pixel, u_size));
    uint lane = gl_LocalInvocationIndex;
    dvec2 local = dvec2(gl_LocalInvocationID.xy);
    dvec2 origin = dvec2(ivec2(gl_WorkGroupID.xy) * (TILE * 256) + 128);
    // (bins past the room were never listed)
    uint begin = min(tile_start[tile], uint(u_bin_room)), end = min(tile_start[tile + 1u], uint(u_bin_room));
    mat3 turn = mat3(u_view);
    // (the chunks before this one left their fragments' lists)
    uint head = inside ? imageLoad(u_head, pixel).x : 0u;
    for (uint batch = begin; batch < end; batch += uint(BATCH)) {
        uint count = min(uint(BATCH), end - batch);
        barrier();
        if (lane < count) {
            int t = int(bins[batch + lane]);
            ivec4 s0 = setup[5 * t], s1 = setup[5 * t + 1], s2 = setup[5 * t + 2];
            held_z[lane] = vec3(intBitsToFloat(s1.z), intBitsToFloat(s1.w), intBitsToFloat(s2.x));
            held_p01[lane] = intBitsToFloat(setup[5 * t + 4]);
            held_p2[lane] = intBitsToFloat(setup[5 * t + 3].zw);
            held_t[lane] = t;
#if !SLIM
            held_placement[lane] = placement_of(u_first + t);
#endif
            dvec3 a = dvec3(edge_eq[9 * t], edge_eq[9 * t + 3], edge_eq[9 * t + 6]);
            dvec3 b = dvec3(edge_eq[9 * t + 1], edge_eq[9 * t + 4], edge_eq[9 * t + 7]);
            dvec3 c = dvec3(edge_eq[9 * t + 2], edge_eq[9 * t + 5], edge_eq[9 * t + 8]);
            held_at[lane] = a * origin.x + b * origin.y + c;
            held_dx[lane] = a * 256.0;
            held_dy[lane] = b * 256.0;
            ivec2 c0 = s0.xy, c1 = s0.zw, c2 = s1.xy;
            held_front[lane] = double(c1.x - c0.x) * double(c2.y - c0.y) - double(c1.y - c0.y) * double(c2.x - c0.x) > 0.0;
        }
        if (lane < uint(BATCH)) {
            tri_count[lane] = 0u;
        }
        barrier();
        float z;
        vec3 w;
        uint hits[BATCH / 32];
        uint mine = 0u;
        for (uint word = 0u; word < uint(BATCH / 32); ++word) {
            uint bits = 0u;
            for (uint k = 32u * word; inside && k < min(count, 32u * word + 32u); ++k) {
                dvec3 e = held_at[k] + held_dx[k] * local.x + held_dy[k] * local.y;
                if (e.x >= 0.0 && e.y >= 0.0 && e.z >= 0.0 && depth_at(k, pixel, z, w)) {
                    bits |= 1u << (k - 32u * word);
                }
            }
            hits[word] = bits;
            mine += uint(bitCount(bits));
        }
        for (uint word = 0u; mine > 0u && word < uint(BATCH / 32); ++word) {
            for (uint bits = hits[word]; bits != 0u; bits &= bits - 1u) {
                atomicAdd(tri_count[32u * word + uint(findLSB(bits))], 1u);
            }
        }
        barrier();
        // where each triangle's fragments start: an inclusive scan of the counts, then less each
        if (lane < uint(BATCH)) {
            tri_next[lane] = tri_count[lane];
        }
        barrier();
        for (uint d = 1u; d < uint(BATCH); d <<= 1) {
            uint before = lane < uint(BATCH) && lane >= d ? tri_next[lane - d] : 0u;
            barrier();
            if (lane < uint(BATCH)) {
                tri_next[lane] += before;
            }
            barrier();
        }
        uint total = tri_next[BATCH - 1];
        uint start = lane < uint(BATCH) ? tri_next[lane] - tri_count[lane] : 0u;
        barrier();
        if (lane < uint(BATCH)) {
            tri_next[lane] = start;
        }
        if (lane == 0u) {
            group_base = atomicAdd(drawn, total);
        }
        barrier();
        for (uint word = 0u; mine > 0u && word < uint(BATCH / 32); ++word) {
            uint bits = hits[word];
            while (bits != 0u) {
                uint k = 32u * word + uint(findLSB(bits));
                bits &= bits - 1u;
                uint node = group_base + atomicAdd(tri_next[k], 1u);
                depth_at(k, pixel, z, w);
                bool front = held_front[k];
#if SLIM
                if (node < capacity) {
                    slim[node] = uvec2(floatBitsToUint(z) | (front ? 0u : KB_BACK), uint(u_first + held_t[k] + 1));
                    AB_SET_LINK(node, head);
                    head = node + 1u;
                }
#else
                if (node < capacity) {
                    ivec4 s2 = setup[5 * held_t[k] + 2];
                    int face = u_first + held_t[k], placed = held_placement[k];
                    vec3 v = w * vec3(intBitsToFloat(s2.y), intBitsToFloat(s2.z), intBitsToFloat(s2.w));
                    v /= v.x + v.y + v.z;
                    uint f = placed_face(placed, face);
                    uint v0 = indices[3u * f], v1 = indices[3u * f + 1u], v2 = indices[3u * f + 2u];
                    vec3 n = normalize(turn * placed_normal(placed, v.x * normal(v0) + v.y * normal(v1) + v.z * normal(v2)));
                    vec3 at = placed_point(placed, v.x * position(v0) + v.y * position(v1) + v.z * position(v2));
                    vec3 eye = (u_view * vec4(at, 1.0)).xyz;
                    vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -eye;
                    if (dot(n, to_eye) < 0.0) {
                        n = -n;
                    }
                    int part = floatBitsToInt(vertices[7u * v0 + 6u]) + placement_part(placed);
                    AB_SET_NODE(node, kb_pack(z, !front, n, face, part));
                    AB_SET_LINK(node, head);
                    head = node + 1u;
                }
#endif
            }
        }
    }
    if (inside) {
        imageStore(u_head, pixel, uvec4(head));
    }
}
#endif

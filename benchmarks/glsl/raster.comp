// The A-buffer's geometry pass (abuffer.frag) done in compute, for benchmarks/compute_capture.py:
// triangles snapped to 1/256 pixel as a rasteriser snaps them, binned to tiles of TILE x TILE
// pixels, and each tile's pixels tested against its triangles by one workgroup, every covered
// pixel centre's fragment appended to the pixel's list as the fragment shader appends it.
// STAGE 0 sets each triangle up and counts the tiles it touches, 1 turns the counts into
// where each tile's triangles start, 2 lists the triangles of each tile, 3 rasterises.
#extension GL_ARB_shading_language_packing : require
#include "blueprint.render:glsl/kbuffer.glsl"
#include "blueprint.render:glsl/abuffer.glsl"

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

// the mesh's interleaved vertices (position, normal, part as int bits) and faces
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
layout(binding = 0, r32ui) coherent uniform uimage2D u_head;

uniform mat4 u_view;
uniform mat4 u_projection;
uniform bool u_ortho;
uniform ivec2 u_size;
uniform int u_triangles;
uniform int u_tile_columns;
uniform int u_tiles;
uniform int u_bin_room;

vec3 position(uint v) { return vec3(vertices[7u * v], vertices[7u * v + 1u], vertices[7u * v + 2u]); }
vec3 normal(uint v) { return vec3(vertices[7u * v + 3u], vertices[7u * v + 4u], vertices[7u * v + 5u]); }

#if STAGE == 0 || STAGE == 2
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

#if STAGE == 0
void main() {
    int t = int(gl_GlobalInvocationID.x);
    if (t >= u_triangles) {
        return;
    }
    ivec2 corner[3];
    vec2 exact[3];
    float z[3], inv_w[3];
    bool behind = false;
    for (int k = 0; k < 3; ++k) {
        vec4 clip = u_projection * (u_view * vec4(position(indices[3 * t + k]), 1.0));
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
    setup[5 * t] = ivec4(corner[0], corner[1]);
    setup[5 * t + 1] = ivec4(corner[2], floatBitsToInt(z[0]), floatBitsToInt(z[1]));
    setup[5 * t + 2] = ivec4(floatBitsToInt(z[2]), floatBitsToInt(inv_w[0]), floatBitsToInt(inv_w[1]),
        floatBitsToInt(inv_w[2]));
    // (a vertex behind the eye needs clipping, which this experiment leaves out: the benchmark
    // refuses such views)
    if (behind || area == 0.0 || any(greaterThan(first, last))) {
        setup[5 * t + 3] = ivec4(0);
        return;
    }
    ivec2 tile0 = first / TILE, tile1 = last / TILE;
    setup[5 * t + 3] = ivec4(tile0.x | (tile0.y << 16), tile1.x | (tile1.y << 16), floatBitsToInt(exact[2]));
    setup[5 * t + 4] = ivec4(floatBitsToInt(exact[0]), floatBitsToInt(exact[1]));
    for (int y = tile0.y; y <= tile1.y; ++y) {
        for (int x = tile0.x; x <= tile1.x; ++x) {
            atomicAdd(tile_count[y * u_tile_columns + x], 1u);
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
    }
}
#elif STAGE == 2
void main() {
    int t = int(gl_GlobalInvocationID.x);
    ivec2 first, last;
    if (t >= u_triangles || !tiles_of(t, first, last)) {
        return;
    }
    for (int y = first.y; y <= last.y; ++y) {
        for (int x = first.x; x <= last.x; ++x) {
            uint tile = uint(y * u_tile_columns + x);
            uint at = tile_start[tile] + atomicAdd(tile_count[tile], 1u);
            if (at < uint(u_bin_room)) {
                bins[at] = uint(t);
            }
        }
    }
}
#else
shared ivec4 held[TILE * TILE * 5];
shared int held_face[TILE * TILE];

// twice the signed area of (a, b, p), exact: corners are integers below 2^26
double edge(ivec2 a, ivec2 b, ivec2 p) {
    return double(b.x - a.x) * double(p.y - a.y) - double(b.y - a.y) * double(p.x - a.x);
}

// a pixel centre on an edge belongs to the triangle on the edge's left or top side only, so
// that two triangles sharing the edge do not both draw it
bool owns(ivec2 a, ivec2 b) {
    ivec2 d = b - a;
    return d.y < 0 || (d.y == 0 && d.x < 0);
}

shared uint group_total;
shared uint group_base;

// whether the pixel centre lies in held triangle k, with its depth, barycentrics and facing
bool covers(uint k, ivec2 pixel, out float z, out vec3 b, out bool front) {
    ivec2 sample_at = pixel * 256 + 128;
    ivec4 s0 = held[5u * k], s1 = held[5u * k + 1u], s2 = held[5u * k + 2u];
    ivec2 c0 = s0.xy, c1 = s0.zw, c2 = s1.xy;
    front = edge(c0, c1, c2) > 0.0;
    if (!front) {
        ivec2 swap = c1;
        c1 = c2;
        c2 = swap;
    }
    double e0 = edge(c1, c2, sample_at), e1 = edge(c2, c0, sample_at), e2 = edge(c0, c1, sample_at);
    if (!((e0 > 0.0 || (e0 == 0.0 && owns(c1, c2))) && (e1 > 0.0 || (e1 == 0.0 && owns(c2, c0)))
            && (e2 > 0.0 || (e2 == 0.0 && owns(c0, c1))))) {
        return false;
    }
    // the plane of depth through the projected corners, at the pixel centre
    vec2 p0 = intBitsToFloat(held[5u * k + 4u].xy), p1 = intBitsToFloat(held[5u * k + 4u].zw);
    vec2 p2 = intBitsToFloat(held[5u * k + 3u].zw);
    vec2 d10 = p1 - p0, d20 = p2 - p0, at = vec2(pixel) + 0.5 - p0;
    float twice = d10.x * d20.y - d20.x * d10.y;
    b.y = (at.x * d20.y - d20.x * at.y) / twice;
    b.z = (d10.x * at.y - at.x * d10.y) / twice;
    b.x = 1.0 - b.y - b.z;
    vec3 zs = vec3(intBitsToFloat(s1.z), intBitsToFloat(s1.w), intBitsToFloat(s2.x));
    z = zs.x + b.y * (zs.y - zs.x) + b.z * (zs.z - zs.x);
    return z >= 0.0 && z <= 1.0;
}

// The workgroup owns its tile's pixels: each pixel's list head stays in a register and is
// stored once, and the fragments of a batch of triangles take their nodes with one atomic on
// the fragment counter for the whole group (counted first, then written), where the fragment
// shader spends an atomic on the counter and one on the head a fragment.
void main() {
    uint tile = gl_WorkGroupID.y * uint(u_tile_columns) + gl_WorkGroupID.x;
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    bool inside = all(lessThan(pixel, u_size));
    uint lane = gl_LocalInvocationIndex;
    uint begin = tile_start[tile], end = tile_start[tile + 1u];
    mat3 turn = mat3(u_view);
    uint head = 0u;
    for (uint batch = begin; batch < end; batch += uint(TILE * TILE)) {
        uint count = min(uint(TILE * TILE), end - batch);
        barrier();
        if (lane < count) {
            int t = int(bins[batch + lane]);
            for (int j = 0; j < 5; ++j) {
                held[5u * lane + uint(j)] = setup[5 * t + j];
            }
            held_face[lane] = t;
        }
        if (lane == 0u) {
            group_total = 0u;
        }
        barrier();
        float z;
        vec3 b;
        bool front;
        uint mine = 0u;
        for (uint k = 0u; inside && k < count; ++k) {
            mine += covers(k, pixel, z, b, front) ? 1u : 0u;
        }
        uint offset = atomicAdd(group_total, mine);
        barrier();
        if (lane == 0u) {
            group_base = atomicAdd(drawn, group_total);
        }
        barrier();
        uint node = group_base + offset;
        for (uint k = 0u; mine > 0u && k < count; ++k) {
            if (!covers(k, pixel, z, b, front)) {
                continue;
            }
#if SLIM
            if (node < capacity) {
                slim[node] = uvec2(floatBitsToUint(z) | (front ? 0u : KB_BACK), uint(held_face[k] + 1));
                AB_SET_LINK(node, head);
                head = node + 1u;
            }
#else
            if (node < capacity) {
                ivec4 s2 = held[5u * k + 2u];
                int face = held_face[k];
                vec3 w = b * vec3(intBitsToFloat(s2.y), intBitsToFloat(s2.z), intBitsToFloat(s2.w));
                w /= w.x + w.y + w.z;
                uint v0 = indices[3 * face], v1 = indices[3 * face + 1], v2 = indices[3 * face + 2];
                vec3 n = normalize(turn * (w.x * normal(v0) + w.y * normal(v1) + w.z * normal(v2)));
                vec3 eye = (u_view * vec4(w.x * position(v0) + w.y * position(v1) + w.z * position(v2), 1.0)).xyz;
                vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -eye;
                if (dot(n, to_eye) < 0.0) {
                    n = -n;
                }
                int part = floatBitsToInt(vertices[7u * v0 + 6u]);
                AB_SET_NODE(node, kb_pack(z, !front, n, face, part));
                AB_SET_LINK(node, head);
                head = node + 1u;
            }
#endif
            node += 1u;
        }
    }
    if (inside) {
        imageStore(u_head, pixel, uvec4(head));
    }
}
#endif

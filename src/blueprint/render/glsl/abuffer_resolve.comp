// Each pixel's fragments in the layers depth peeling would draw (peel.frag): sorted by their
// depth as a 24-bit depth buffer holds it (back faces u_back_bias behind) and then by primitive
// (the first drawn wins a tie), the first is layer 0, and each next layer is the first fragment
// after it lying more than u_peel_eps (eye depth) behind it. Its own depth is kept whole, not
// rounded to the depth buffer's steps: a rounding that differs from the driver's by a step here
// and there is noise to the edges' second differences of depth. The layers are
// chained through AB_ORDER from u_cursor (node + 1; 0 ends the chain). With SLIM (abuffer.frag)
// the fragments hold depth and face alone, and each one kept as a layer gets its whole node
// here: the normal and part of its face at the pixel centre, as the geometry pass would have made.
#extension GL_ARB_shading_language_packing : require
layout(local_size_x = 8, local_size_y = 8) in;
#include "depth.glsl"
#include "kbuffer.glsl"
#include "abuffer.glsl"
#if SLIM
#include "instance.glsl"
#endif

// lists up to this long are sorted in registers; longer ones are walked once a layer, which
// costs most where lists run long
#define SORTED 48

layout(binding = 0, r32ui) readonly uniform uimage2D u_head;
layout(binding = 1, r32ui) writeonly uniform uimage2D u_cursor;
// each pixel's layers: whether a layer covers a pixel, for passes that walk only some chains
layout(binding = 2, r32ui) writeonly uniform uimage2D u_layer_count;
uniform float u_back_bias;
uniform float u_peel_eps;

#if SLIM
// the mesh (render.mesh.GpuMesh): 7 words a vertex (position, normal, part), 3 indices a face,
// each face placed by its instance (instance.glsl's faces table)
layout(std430, binding = 8) readonly buffer Vertices {
    float vertices[];
};
layout(std430, binding = 9) readonly buffer Indices {
    uint indices[];
};
uniform mat4 u_view;
uniform mat4 u_projection;
uniform bool u_ortho;
uniform vec2 u_target;  // the pixels of the G-buffer

vec3 vertex_vec3(uint v, uint at) {
    return vec3(vertices[7u * v + at], vertices[7u * v + at + 1u], vertices[7u * v + at + 2u]);
}

// fragment i at pixel p kept as a layer: its whole node. The weights of the face's corners at
// the pixel centre are the perspective-correct ones the rasteriser interpolates with: those
// whose clip position projects to the centre (two planes through the eye, crossed).
void keep(ivec2 p, uint i) {
    uvec2 s = slim[i];
    uint face = s.y - 1u;
    int placed = placement_of(int(face));
    uint f = placed_face(placed, int(face));
    vec2 q = (vec2(p) + 0.5) / u_target * 2.0 - 1.0;
    vec3 eye[3];
    vec3 normal[3];
    vec3 across_x;
    vec3 across_y;
    int part = 0;
    for (int k = 0; k < 3; ++k) {
        uint v = indices[3u * f + uint(k)];
        vec4 e = u_view * vec4(placed_point(placed, vertex_vec3(v, 0u)), 1.0);
        vec4 c = u_projection * e;
        eye[k] = e.xyz;
        normal[k] = mat3(u_view) * placed_normal(placed, vertex_vec3(v, 3u));
        across_x[k] = c.x - q.x * c.w;
        across_y[k] = c.y - q.y * c.w;
        part = floatBitsToInt(vertices[7u * v + 6u]) + placement_part(placed);
    }
    vec3 w = cross(across_x, across_y);
    w /= w.x + w.y + w.z;
    vec3 n = normalize(w.x * normal[0] + w.y * normal[1] + w.z * normal[2]);
    vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -(w.x * eye[0] + w.y * eye[1] + w.z * eye[2]);
    // two-sided, as peel.frag
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    AB_SET_NODE(i, kb_pack(uintBitsToFloat(s.x & ~KB_BACK), (s.x & KB_BACK) != 0u, n, int(face), part));
}
#else
void keep(ivec2 p, uint i) {
}
#endif

// the depth the depth buffer holds for a fragment: 24-bit fixed point
uint held_depth(uvec4 s) {
    return uint(kb_depth(s, u_back_bias) * 16777215.0 + 0.5);
}

// whether (depth a, face a) sorts before (depth b, face b)
bool before(uint da, uint fa, uint db, uint fb) {
    return da < db || (da == db && fa < fb);
}

// the eye depth behind which the layer after surface s lies
float next_after(uvec4 s) {
    return eye_depth(kb_depth(s, u_back_bias)) + u_peel_eps;
}

// the pixel's layers, chained from its cursor; how many
uint chain(ivec2 p) {
    // The short list sorted by insertion of one word an entry, its held depth above its place
    // in the list (SORTED <= 256): what an insertion moves is that word alone, where llvmpipe
    // moves each array a lane at a time. Node, face and depth bits stay at the list's place j:
    // held in arrays where the lists are images (llvmpipe's image loads cost more than the
    // arrays); read again from the fragment on a GPU, where arrays live in the threads' local
    // memory and the fragment, just read, in its cache.
    uint sorted[SORTED];
    uint node[SORTED];
#if AB_IMAGES
    uint face[SORTED];
    uint bits[SORTED];
#define FACE_AT(j) face[j]
#define BITS_AT(j) bits[j]
#else
#define FACE_AT(j) fragment(node[j] - 1u).w
#define BITS_AT(j) fragment(node[j] - 1u).x
#endif
    uint n = 0u;
    uint at = imageLoad(u_head, p).x;
    uint head = at;
    while (at != 0u && n < SORTED) {
        uvec4 s = fragment(at - 1u);
        node[n] = at;
#if AB_IMAGES
        face[n] = s.w;
        bits[n] = s.x;
#endif
        uint k = held_depth(s);
        uint i = n;
        while (i > 0u) {
            uint other = sorted[i - 1u];
            // (depth, face) order, as before(): a face looked up on equal depths alone
            if ((other >> 8) < k || ((other >> 8) == k && FACE_AT(other & 0xffu) <= s.w)) {
                break;
            }
            sorted[i] = other;
            --i;
        }
        sorted[i] = (k << 8) | n;
        ++n;
        at = AB_LINK(at - 1u);
    }
    uint layers = 0u;
    uint first = 0u;
    uint last = 0u;
    if (at == 0u) {
        float behind = -1.0 / 0.0;
        for (uint i = 0u; i < n; ++i) {
            uint j = sorted[i] & 0xffu;
            uvec4 s = uvec4(BITS_AT(j), 0u, 0u, 0u);
            if (layers > 0u && eye_depth(kb_raw(s)) <= behind) {
                continue;
            }
            keep(p, node[j] - 1u);
            if (last == 0u) {
                first = node[j];
            } else {
                AB_SET_ORDER(last - 1u, node[j]);
            }
            last = node[j];
            behind = next_after(s);
            ++layers;
        }
    } else {
        // a long list: each layer is the least (depth, face) of the fragments behind the last
        atomicAdd(long_lists, 1u);
        float behind = -1.0 / 0.0;
        while (true) {
            uint best = 0u;
            uint best_key = 0xffffffffu;
            uint best_face = 0xffffffffu;
            for (uint a = head; a != 0u; a = AB_LINK(a - 1u)) {
                uvec4 s = fragment(a - 1u);
                if (layers > 0u && eye_depth(kb_raw(s)) <= behind) {
                    continue;
                }
                uint k = held_depth(s);
                if (best == 0u || before(k, s.w, best_key, best_face)) {
                    best = a;
                    best_key = k;
                    best_face = s.w;
                }
            }
            if (best == 0u) {
                break;
            }
            if (last == 0u) {
                first = best;
            } else {
                AB_SET_ORDER(last - 1u, best);
            }
            last = best;
            keep(p, best - 1u);
            behind = next_after(fragment(best - 1u));
            ++layers;
        }
    }
    if (last != 0u) {
        AB_SET_ORDER(last - 1u, 0u);
    }
    imageStore(u_cursor, p, uvec4(first));
    return layers;
}

#if COUNTED_AFTER
// The counts are left to the caller, which reads u_layer_count back (a software rasteriser,
// where that costs a copy): the group's histogram, its barriers and shared atomics, cost much
// of the resolve there. There the groups run only over the tiles listed as holding a
// fragment (TILES): a software rasteriser runs all of a group's code, empty or not, and the
// caller has cleared the counts and cursors of the rest.
#define TILE_LIST_BINDING 3
#include "abuffer_tiles.glsl"

void main() {
    ivec2 p = listed_pixel();
    if (p.x >= 0 && all(lessThan(p, imageSize(u_head)))) {
        imageStore(u_layer_count, p, uvec4(chain(p)));
    }
}
#else
shared uint group_pixels_with[MOST_LAYERS + 1];

void main() {
    // the histogram of layers a pixel, counted in the group first: one global atomic a group
    // and count instead of one a pixel
    for (uint i = gl_LocalInvocationIndex; i <= MOST_LAYERS; i += 64u) {
        group_pixels_with[i] = 0u;
    }
    barrier();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (all(lessThan(p, imageSize(u_head)))) {
        uint layers = chain(p);
        imageStore(u_layer_count, p, uvec4(layers));
        atomicAdd(group_pixels_with[min(layers, uint(MOST_LAYERS))], 1u);
    }
    barrier();
    for (uint i = gl_LocalInvocationIndex; i <= MOST_LAYERS; i += 64u) {
        if (i > 0u && group_pixels_with[i] > 0u) {
            atomicAdd(pixels_with[i], group_pixels_with[i]);
        }
    }
}
#endif

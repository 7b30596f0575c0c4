// Each pixel's fragments in the layers depth peeling would draw (peel.frag): sorted by their
// depth as a 24-bit depth buffer holds it (back faces u_back_bias behind) and then by primitive
// (the first drawn wins a tie), the first is layer 0, and each next layer is the first fragment
// after it lying more than u_peel_eps (eye depth) behind it. Its own depth is kept whole, not
// rounded to the depth buffer's steps: a rounding that differs from the driver's by a step here
// and there is noise to the edges' second differences of depth. The layers are
// chained through AB_ORDER from u_cursor (node + 1; 0 ends the chain). With SLIM (abuffer.frag)
// the fragments hold depth and face alone, and each one kept as a layer gets its whole node
// here: the normal and part of its face at the pixel centre, as the geometry pass would have made.
// A list too long to sort in registers is left to a second dispatch (LONG) over those pixels
// alone: sorted SORTED fragments at a time into runs chained through AB_ORDER, each run merged
// into the runs before it. A fragment costs some comparisons a run, where walking the list
// once a layer cost one a layer, and a list of 255 layers ran past llvmpipe's 65 535 turns of
// a loop, losing every layer; in a dispatch of its own, this code costs the short lists'
// nothing (a software rasteriser runs a branch no lane takes).
#extension GL_ARB_shading_language_packing : require
#if LONG
layout(local_size_x = 64) in;
#else
layout(local_size_x = 8, local_size_y = 8) in;
#endif
#include "depth.glsl"
#include "kbuffer.glsl"
#include "abuffer.glsl"
#if SLIM
#include "instance.glsl"
#endif

// lists up to SORTED fragments long (abuffer.py's) are sorted in registers

layout(binding = 0, r32ui) readonly uniform uimage2D u_head;
layout(binding = 1, r32ui) writeonly uniform uimage2D u_cursor;
// each pixel's layers: whether a layer covers a pixel, for passes that walk only some chains
layout(binding = 2, r32ui) writeonly uniform uimage2D u_layer_count;
// the groups of the dispatch over the long lists' pixels, the lists too long for it (LONG_MOST)
// and the pixels (x | y << 16)
layout(std430, binding = LONG_BINDING) coherent buffer Long {
    uint long_groups[3];
    uint too_long;
    uint long_pixels[];
};
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

// fragment s at node a (+ 1), the next in (depth, face) order, made the pixel's next layer where
// it lies behind the last one: the layers so far chained from first to last (nodes + 1), how
// many, and the eye depth the next must lie behind
void add_layer(
    ivec2 p, uint a, uvec4 s, inout uint first, inout uint last, inout uint layers, inout float behind
) {
    if (layers > 0u && eye_depth(kb_raw(s)) <= behind) {
        return;
    }
    keep(p, a - 1u);
    if (last == 0u) {
        first = a;
    } else {
        AB_SET_ORDER(last - 1u, a);
    }
    last = a;
    behind = next_after(s);
    ++layers;
}

// the sorted chains from nodes a and b (+ 1; a may be 0: none) merged into one through
// AB_ORDER, in (depth, face) order; its first node + 1
uint merged(uint a, uint b) {
    if (a == 0u) {
        return b;
    }
    uvec4 sa = fragment(a - 1u);
    uvec4 sb = fragment(b - 1u);
    uint ka = held_depth(sa);
    uint kb = held_depth(sb);
    uint head = 0u;
    uint tail = 0u;
    while (a != 0u && b != 0u) {
        uint taken;
        // each chain's next read before the last one taken is linked to this one
        if (before(ka, sa.w, kb, sb.w)) {
            taken = a;
            a = AB_ORDER(a - 1u);
            if (a != 0u) {
                sa = fragment(a - 1u);
                ka = held_depth(sa);
            }
        } else {
            taken = b;
            b = AB_ORDER(b - 1u);
            if (b != 0u) {
                sb = fragment(b - 1u);
                kb = held_depth(sb);
            }
        }
        if (tail == 0u) {
            head = taken;
        } else {
            AB_SET_ORDER(tail - 1u, taken);
        }
        tail = taken;
    }
    AB_SET_ORDER(tail - 1u, a != 0u ? a : b);
    return head;
}

// the pixel's layers, chained from its cursor; how many (a long list's: 0, and its pixel
// listed for the second dispatch)
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
    uint at = imageLoad(u_head, p).x;
    uint n;
#if LONG
    uint sorted_chain = 0u;  // the runs merged so far
    do {
#endif
        n = 0u;
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
#if LONG
        // a run: chained in order, merged into the runs before it
        for (uint i = 0u; i + 1u < n; ++i) {
            AB_SET_ORDER(node[sorted[i] & 0xffu] - 1u, node[sorted[i + 1u] & 0xffu]);
        }
        AB_SET_ORDER(node[sorted[n - 1u] & 0xffu] - 1u, 0u);
        sorted_chain = merged(sorted_chain, node[sorted[0] & 0xffu]);
    } while (at != 0u);
#else
        if (at != 0u) {
            // a long list: left to the second dispatch
            uint k = atomicAdd(long_lists, 1u);
            long_pixels[k] = uint(p.x) | (uint(p.y) << 16);
            if (k % 64u == 0u) {
                atomicAdd(long_groups[0], 1u);
            }
            return 0u;
        }
#endif
    uint layers = 0u;
    uint first = 0u;
    uint last = 0u;
    float behind = -1.0 / 0.0;
#if LONG
    // each layer the merged chain's next fragment lying behind the last
    for (uint a = sorted_chain; a != 0u;) {
        uint next = AB_ORDER(a - 1u);
        add_layer(p, a, fragment(a - 1u), first, last, layers, behind);
        a = next;
    }
#else
    for (uint i = 0u; i < n; ++i) {
        uint j = sorted[i] & 0xffu;
        // the depth bits are all a layer's test reads
        add_layer(p, node[j], uvec4(BITS_AT(j), 0u, 0u, 0u), first, last, layers, behind);
    }
#endif
    if (last != 0u) {
        AB_SET_ORDER(last - 1u, 0u);
    }
    imageStore(u_cursor, p, uvec4(first));
    return layers;
}

#if LONG
// the long lists' pixels, one an invocation
void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k < long_lists) {
        uint at = long_pixels[k];
        ivec2 p = ivec2(int(at & 0xffffu), int(at >> 16));
#ifdef LONG_MOST
        // a software rasteriser ends an invocation's loops after 65 535 turns in all, which a
        // sort of more than LONG_MOST fragments could pass, losing the pixel's layers: such a
        // list is counted instead, and the caller peels the frame
        uint n = 0u;
        for (uint a = imageLoad(u_head, p).x; a != 0u && n <= uint(LONG_MOST); a = AB_LINK(a - 1u)) {
            ++n;
        }
        if (n > uint(LONG_MOST)) {
            atomicAdd(too_long, 1u);
            return;
        }
#endif
        uint layers = chain(p);
        imageStore(u_layer_count, p, uvec4(layers));
#if !COUNTED_AFTER
        atomicAdd(pixels_with[min(layers, uint(MOST_LAYERS))], 1u);
#endif
    }
}
#elif COUNTED_AFTER
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

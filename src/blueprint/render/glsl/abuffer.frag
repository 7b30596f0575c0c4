// Geometry pass of the A-buffer: every fragment of the mesh, unordered, is appended to its
// pixel's list (abuffer.glsl); nothing is tested, nothing drawn. Fragments beyond the nodes
// held are counted and dropped: the capture sees the count and draws again with room for them.
// With SLIM a fragment is its depth and face alone, 8 bytes instead of 16: where the graphics
// pipeline runs on a few of the GPU's cores the pass is bound by the bytes its
// fragments write (benchmarks/capture_cost.py), and the resolve, in compute on all of them,
// finds the normal and part of the fragments that become layers from their faces.
#extension GL_ARB_shading_language_packing : require
#if FETCH_HEAD
#extension GL_EXT_shader_framebuffer_fetch : require
#endif
#if BALLOT
#extension GL_ARB_shader_ballot : require
#extension GL_ARB_gpu_shader_int64 : require
#extension GL_ARB_ES3_1_compatibility : require
#endif
#include "depth.glsl"
#include "fragment_depth.glsl"
#include "kbuffer.glsl"
#include "abuffer.glsl"

#if FETCH_HEAD
// the pixel's head as its target: a pixel's fragments read and write it one after another, so
// each links the last one's node without an atomic, which a software rasteriser runs a lane at
// a time
layout(location = 0) inout uint o_head;
#define PUSH(node) AB_SET_LINK(node, o_head); o_head = node + 1u
#else
layout(binding = 0, r32ui) coherent uniform uimage2D u_head;
#define PUSH(node) AB_SET_LINK(node, imageAtomicExchange(u_head, ivec2(gl_FragCoord.xy), node + 1u))
#endif
uniform bool u_ortho;

#if BALLOT
// the fragment's node: the subgroup's fragments take theirs with one atomic, where an atomic on
// a storage buffer runs a lane at a time on a software rasteriser.
// Helper invocations take no part: an atomic of theirs does nothing, so one of them leading
// would hand out nodes already taken, and lists that share nodes can run in circles.
uint next_node() {
    uint64_t lanes = ballotARB(!gl_HelperInvocation);
    uvec2 halves = unpackUint2x32(lanes);
    uint count = uint(bitCount(halves.x) + bitCount(halves.y));
    int leader = halves.x != 0u ? findLSB(halves.x) : 32 + findLSB(halves.y);
    uint base = 0u;
    if (int(gl_SubGroupInvocationARB) == leader) {
        base = atomicAdd(drawn, count);
    }
    base = readInvocationARB(base, uint(leader));
    uvec2 below = unpackUint2x32(gl_SubGroupLtMaskARB & lanes);
    return base + uint(bitCount(below.x) + bitCount(below.y));
}
#else
uint next_node() {
    return atomicAdd(drawn, 1u);
}
#endif

in vec3 v_eye;
in vec3 v_normal;
flat in int v_part;
flat in int v_first_face;  // the instance's (geometry.vert)

void main() {
    float z = fragment_depth();
#if SLIM
    uint node = next_node();
    if (node < capacity) {
        slim[node] = uvec2(floatBitsToUint(z) | (gl_FrontFacing ? 0u : KB_BACK), uint(v_first_face + gl_PrimitiveID + 1));
        PUSH(node);
    }
#else
    vec3 n = normalize(v_normal);
    vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -v_eye;
    // two-sided, as peel.frag
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    // faces cost a GPU nothing, and order the fragments of one depth as drawing them would
    int face = v_first_face + gl_PrimitiveID;
    uint node = next_node();
    if (node < capacity) {
        AB_SET_NODE(node, kb_pack(z, !gl_FrontFacing, n, face, v_part));
        PUSH(node);
    }
#endif
}

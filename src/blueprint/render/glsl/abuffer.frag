// Geometry pass of the A-buffer: every fragment of the mesh, unordered, is appended to its
// pixel's list (abuffer.glsl); nothing is tested, nothing drawn. Fragments beyond the nodes
// held are counted and dropped: the capture sees the count and draws again with room for them.
// With SLIM a fragment is its depth and face alone, 8 bytes instead of 16: where the graphics
// pipeline runs on a few of the GPU's cores (the H200) the pass is bound by the bytes its
// fragments write (benchmarks/capture_cost.py), and the resolve, in compute on all of them,
// finds the normal and part of the fragments that become layers from their faces.
#extension GL_ARB_shading_language_packing : require
#include "depth.glsl"
#include "fragment_depth.glsl"
#include "kbuffer.glsl"
#include "abuffer.glsl"

layout(binding = 0, r32ui) coherent uniform uimage2D u_head;
uniform bool u_ortho;

in vec3 v_eye;
in vec3 v_normal;
flat in int v_part;

void main() {
    float z = fragment_depth();
#if SLIM
    uint node = atomicAdd(drawn, 1u);
    if (node < capacity) {
        slim[node] = uvec2(floatBitsToUint(z) | (gl_FrontFacing ? 0u : KB_BACK), uint(gl_PrimitiveID + 1));
        AB_SET_LINK(node, imageAtomicExchange(u_head, ivec2(gl_FragCoord.xy), node + 1u));
    }
#else
    vec3 n = normalize(v_normal);
    vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -v_eye;
    // two-sided, as peel.frag
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    // faces cost a GPU nothing, and order the fragments of one depth as drawing them would
    int face = gl_PrimitiveID;
    uint node = atomicAdd(drawn, 1u);
    if (node < capacity) {
        AB_SET_NODE(node, kb_pack(z, !gl_FrontFacing, n, face, v_part));
        AB_SET_LINK(node, imageAtomicExchange(u_head, ivec2(gl_FragCoord.xy), node + 1u));
    }
#endif
}

// Variants of the A-buffer's geometry pass (render/glsl/abuffer.frag), to find what bounds it
// (benchmarks/capture_cost.py). VARIANT:
//   1  the product's pass without exact depth (gl_FragCoord.z)
//   2  a node of the depth and the face alone (8 bytes), with the link
//   3  as 2, the node counter taken once a subgroup (ARB_shader_ballot)
//   4  as 1, the node counter taken once a subgroup
//   5  the counter alone: no node, no link
//   6  nothing written: the rasteriser and the shader's launch
//   7  the product's pass (exact depth where the renderer takes it), the counter once a subgroup
//   8  as 2, with exact depth where the renderer takes it, the list heads in a storage buffer
//      instead of an image
//   9  as 2, with exact depth where the renderer takes it: no links, the first FIXED fragments
//      of a pixel in slots of their own (slot k of every pixel together), counted per pixel
//      in a storage buffer (fragments past FIXED are dropped: a lower bound)
//  10  a node of the face alone (4 bytes: depth found later from the face), with the link
//  11  as 9, a slot of the face alone (4 bytes)
#extension GL_ARB_shading_language_packing : require
#if VARIANT == 3 || VARIANT == 4 || VARIANT == 7
#extension GL_ARB_shader_ballot : require
#extension GL_ARB_gpu_shader_int64 : require
#endif
#include "depth.glsl"
#include "fragment_depth.glsl"
#include "blueprint.render:glsl/kbuffer.glsl"

layout(std430, binding = 0) coherent buffer Nodes {
    uvec4 nodes[];
};
layout(std430, binding = 1) coherent buffer Links {
    uint links[];
};
layout(std430, binding = 3) coherent buffer Totals {
    uint drawn;
    uint capacity;
    uint deepest;
    uint long_lists;
};
layout(std430, binding = 7) coherent buffer Small {
    uvec2 small[];
};
layout(std430, binding = 10) coherent buffer Heads {
    uint heads[];
};
layout(std430, binding = 11) coherent buffer Faces {
    uint faces[];
};
#define FIXED 16
layout(binding = 0, r32ui) coherent uniform uimage2D u_head;
uniform int u_width;
uniform int u_pixels;
uniform bool u_ortho;

in vec3 v_eye;
in vec3 v_normal;
flat in int v_part;

#if VARIANT == 3 || VARIANT == 4 || VARIANT == 7
uint next_node() {
    bool live = !gl_HelperInvocation;
    uint64_t lanes = ballotARB(live);
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

void main() {
#if VARIANT == 6
    if (gl_FragCoord.z < -1.0) {
        drawn = 1u;
    }
#elif VARIANT == 5
    atomicAdd(drawn, 1u);
#elif VARIANT == 8
    float z = fragment_depth();
    uint node = atomicAdd(drawn, 1u);
    if (node < capacity) {
        small[node] = uvec2(floatBitsToUint(z) | (gl_FrontFacing ? 0u : KB_BACK), uint(gl_PrimitiveID + 1));
        ivec2 q = ivec2(gl_FragCoord.xy);
        links[node] = atomicExchange(heads[q.y * u_width + q.x], node + 1u);
    }
#elif VARIANT == 9 || VARIANT == 11
    ivec2 q = ivec2(gl_FragCoord.xy);
    int pixel = q.y * u_width + q.x;
    uint k = atomicAdd(heads[pixel], 1u);
    if (k < uint(FIXED)) {
#if VARIANT == 9
        small[int(k) * u_pixels + pixel] = uvec2(floatBitsToUint(fragment_depth()) | (gl_FrontFacing ? 0u : KB_BACK), uint(gl_PrimitiveID + 1));
#else
        faces[int(k) * u_pixels + pixel] = uint(gl_PrimitiveID + 1) | (gl_FrontFacing ? 0u : KB_BACK);
#endif
    }
#elif VARIANT == 10
    uint node = atomicAdd(drawn, 1u);
    if (node < capacity) {
        faces[node] = uint(gl_PrimitiveID + 1) | (gl_FrontFacing ? 0u : KB_BACK);
        links[node] = imageAtomicExchange(u_head, ivec2(gl_FragCoord.xy), node + 1u);
    }
#elif VARIANT == 2 || VARIANT == 3
    uint node = next_node();
    if (node < capacity) {
        small[node] = uvec2(floatBitsToUint(gl_FragCoord.z) | (gl_FrontFacing ? 0u : KB_BACK), uint(gl_PrimitiveID + 1));
        links[node] = imageAtomicExchange(u_head, ivec2(gl_FragCoord.xy), node + 1u);
    }
#else
#if VARIANT == 7
    float z = fragment_depth();
#else
    float z = gl_FragCoord.z;
#endif
    vec3 n = normalize(v_normal);
    vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -v_eye;
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    uint node = next_node();
    if (node < capacity) {
        nodes[node] = kb_pack(z, !gl_FrontFacing, n, gl_PrimitiveID, v_part);
        links[node] = imageAtomicExchange(u_head, ivec2(gl_FragCoord.xy), node + 1u);
    }
#endif
}

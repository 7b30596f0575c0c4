// Depth peeling K layers in one geometry pass (a k-buffer). Every fragment behind the last layer
// of the previous pass is inserted among the K nearest surfaces found so far at its pixel, kept
// sorted in K integer targets that the shader reads back through framebuffer fetch: the driver
// runs the fragments of one pixel one after another, in primitive order. The rules are those of
// peel.frag, so both give the same layers: back faces lie u_back_bias behind, a fragment no
// more than u_peel_eps (eye depth) behind a surface is that surface (coplanar faces, touching
// parts), and of two fragments at one depth the first drawn stays. With IDS_ONLY a surface is
// its depth and face alone (kbuffer.glsl), for passes that need no normals.
#extension GL_EXT_shader_framebuffer_fetch : require
#extension GL_ARB_shading_language_packing : require
#include "depth.glsl"
#include "kbuffer.glsl"

uniform sampler2D u_prev_depth;
uniform bool u_peel;
uniform float u_peel_eps;
uniform bool u_ortho;
uniform float u_back_bias;

in vec3 v_eye;
in vec3 v_normal;
flat in int v_part;

layout(location = 0) inout KB_T o_s0;
#if K > 1
layout(location = 1) inout KB_T o_s1;
#endif
#if K > 2
layout(location = 2) inout KB_T o_s2;
#endif
#if K > 3
layout(location = 3) inout KB_T o_s3;
#endif
#if K > 4
layout(location = 4) inout KB_T o_s4;
#endif
#if K > 5
layout(location = 5) inout KB_T o_s5;
#endif
#if K > 6
layout(location = 6) inout KB_T o_s6;
#endif
#if K > 7
layout(location = 7) inout KB_T o_s7;
#endif

void main() {
    float z = gl_FragCoord.z;
    if (u_peel) {
        float prev = texelFetch(u_prev_depth, ivec2(gl_FragCoord.xy), 0).r;
        if (prev >= 1.0 || eye_depth(z) <= eye_depth(prev) + u_peel_eps) {
            discard;
        }
    }
#if IDS_ONLY
    vec3 n = vec3(0.0);
#else
    vec3 n = normalize(v_normal);
    vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -v_eye;
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
#endif
#if FACE_IDS
    int face = gl_PrimitiveID;
#else
    int face = -1;
#endif
    KB_T c = kb_pack(z, !gl_FrontFacing, n, face, v_part);
    float cb = kb_depth(c, u_back_bias);

    KB_T s[K];
    s[0] = o_s0;
#if K > 1
    s[1] = o_s1;
#endif
#if K > 2
    s[2] = o_s2;
#endif
#if K > 3
    s[3] = o_s3;
#endif
#if K > 4
    s[4] = o_s4;
#endif
#if K > 5
    s[5] = o_s5;
#endif
#if K > 6
    s[6] = o_s6;
#endif
#if K > 7
    s[7] = o_s7;
#endif
    // The surfaces held come first, and the place after them is empty: only the first target
    // is cleared before a pass, the rest of a pixel's targets are read only up to there.
    int count = K;
    for (int k = 0; k < K; ++k) {
        if (count == K && kb_empty(s[k])) {
            count = k;
        }
    }
    // where the fragment goes: before the first surface it lies in front of (in its place
    // when that surface is within the tolerance behind), or after them all
    int at = count;
    bool same = false;
    for (int k = 0; k < K; ++k) {
        if (k >= count || at < count) {
            continue;
        }
        float sb = kb_depth(s[k], u_back_bias);
        if (cb >= sb) {
            // at or behind this surface: part of it, or on to the next one
            if (eye_depth(z) <= eye_depth(sb) + u_peel_eps) {
                discard;
            }
            continue;
        }
        // in front of it: the peel would take this fragment first and then skip the surface
        // if it lies within the tolerance behind
        at = k;
        same = eye_depth(kb_raw(s[k])) <= eye_depth(cb) + u_peel_eps;
    }
    if (at == K) {
        discard;  // behind all K surfaces
    }
    int held = same ? count : count + 1;
    // constant indices only: llvmpipe miscompiled writes through a computed index
    o_s0 = at == 0 ? c : (0 < held ? s[0] : KB_T(0u));
#if K > 1
    o_s1 = 1 < at ? s[1] : (1 == at ? c : (1 < held ? (same ? s[1] : s[0]) : KB_T(0u)));
#endif
#if K > 2
    o_s2 = 2 < at ? s[2] : (2 == at ? c : (2 < held ? (same ? s[2] : s[1]) : KB_T(0u)));
#endif
#if K > 3
    o_s3 = 3 < at ? s[3] : (3 == at ? c : (3 < held ? (same ? s[3] : s[2]) : KB_T(0u)));
#endif
#if K > 4
    o_s4 = 4 < at ? s[4] : (4 == at ? c : (4 < held ? (same ? s[4] : s[3]) : KB_T(0u)));
#endif
#if K > 5
    o_s5 = 5 < at ? s[5] : (5 == at ? c : (5 < held ? (same ? s[5] : s[4]) : KB_T(0u)));
#endif
#if K > 6
    o_s6 = 6 < at ? s[6] : (6 == at ? c : (6 < held ? (same ? s[6] : s[5]) : KB_T(0u)));
#endif
#if K > 7
    o_s7 = 7 < at ? s[7] : (7 == at ? c : (7 < held ? (same ? s[7] : s[6]) : KB_T(0u)));
#endif
}

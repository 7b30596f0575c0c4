// Depth peeling K layers in one geometry pass (a k-buffer). Every fragment behind the last layer
// of the previous pass is inserted among the K nearest surfaces found so far at its pixel
// (kb_place), kept sorted in K integer targets that the fragments of one pixel read and write
// one after another, in primitive order: through framebuffer fetch (Mesa's drivers), or with
// INTERLOCK as images inside a critical section ordered per pixel (fragment shader interlock,
// NVIDIA's). The rules are those of peel.frag, so both give the same layers: back faces lie
// u_back_bias behind, a fragment no more than u_peel_eps (eye depth) behind a surface is that
// surface (coplanar faces, touching parts), and of two fragments at one depth the first drawn
// stays. With IDS_ONLY (through framebuffer fetch) a surface is its depth and face alone
// (kbuffer.glsl), for passes that need no normals. With COUNT (through framebuffer fetch) one
// more target, after the K surfaces, holds how many surfaces the pixel holds, as count / 255
// (r), for passes that read the surfaces where they lie instead of unpacked, and how many the
// pixel let go behind its K (g, saturating at 255): every fragment behind all K that is part
// of none, and every surface pushed out behind the K-th, one each; the most of these is the
// layers a frame capped at K leaves behind, without remaining.py's pass to count them, which
// costs a software rasteriser much of a capped frame. As that pass counts, coincident surfaces
// count apart. With PEEL the pass finds the layers behind those of an earlier one
// (u_prev_depth); the first pass is built without (a software rasteriser reads the previous
// depth under a uniform branch too).
#if INTERLOCK
#extension GL_ARB_fragment_shader_interlock : require
#else
#extension GL_EXT_shader_framebuffer_fetch : require
#endif
#extension GL_ARB_shading_language_packing : require
#include "depth.glsl"
#include "fragment_depth.glsl"
#include "kbuffer.glsl"

#if PEEL
uniform sampler2D u_prev_depth;
#endif
uniform float u_peel_eps;
uniform bool u_ortho;
uniform float u_back_bias;

in vec3 v_eye;
in vec3 v_normal;
flat in int v_part;
flat in int v_first_face;  // the instance's (geometry.vert)

#if INTERLOCK
layout(pixel_interlock_ordered) in;
layout(binding = 0, rgba32ui) coherent uniform uimage2D u_s0;
#if K > 1
layout(binding = 1, rgba32ui) coherent uniform uimage2D u_s1;
#endif
#if K > 2
layout(binding = 2, rgba32ui) coherent uniform uimage2D u_s2;
#endif
#if K > 3
layout(binding = 3, rgba32ui) coherent uniform uimage2D u_s3;
#endif
#if K > 4
layout(binding = 4, rgba32ui) coherent uniform uimage2D u_s4;
#endif
#if K > 5
layout(binding = 5, rgba32ui) coherent uniform uimage2D u_s5;
#endif
#if K > 6
layout(binding = 6, rgba32ui) coherent uniform uimage2D u_s6;
#endif
#if K > 7
layout(binding = 7, rgba32ui) coherent uniform uimage2D u_s7;
#endif
#else
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
#if COUNT
layout(location = K) inout vec4 o_count;
#endif
#endif

void main() {
    float z = fragment_depth();
    bool keep = true;
#if PEEL
    float prev = texelFetch(u_prev_depth, ivec2(gl_FragCoord.xy), 0).r;
    keep = prev < 1.0 && eye_depth(z) > eye_depth(prev) + u_peel_eps;
#endif
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
    int face = v_first_face + gl_PrimitiveID;
#else
    int face = -1;
#endif
    KB_T c = kb_pack(z, !gl_FrontFacing, n, face, v_part);
    float cb = kb_depth(c, u_back_bias);
    KB_T s[K];
    bool same, merged;
    int held;
#if INTERLOCK
    // the critical section is entered by every fragment, in main's own flow (the extension's
    // rule): fragments left out only skip the writes
    ivec2 p = ivec2(gl_FragCoord.xy);
    beginInvocationInterlockARB();
    s[0] = imageLoad(u_s0, p);
#if K > 1
    s[1] = imageLoad(u_s1, p);
#endif
#if K > 2
    s[2] = imageLoad(u_s2, p);
#endif
#if K > 3
    s[3] = imageLoad(u_s3, p);
#endif
#if K > 4
    s[4] = imageLoad(u_s4, p);
#endif
#if K > 5
    s[5] = imageLoad(u_s5, p);
#endif
#if K > 6
    s[6] = imageLoad(u_s6, p);
#endif
#if K > 7
    s[7] = imageLoad(u_s7, p);
#endif
    int at = kb_place(s, eye_depth(z), cb, u_back_bias, u_peel_eps, same, held, merged);
    if (keep && at < K) {
        imageStore(u_s0, p, KB_SHIFTED(s, c, at, held, same, 0, 0));
#if K > 1
        imageStore(u_s1, p, KB_SHIFTED(s, c, at, held, same, 1, 0));
#endif
#if K > 2
        imageStore(u_s2, p, KB_SHIFTED(s, c, at, held, same, 2, 1));
#endif
#if K > 3
        imageStore(u_s3, p, KB_SHIFTED(s, c, at, held, same, 3, 2));
#endif
#if K > 4
        imageStore(u_s4, p, KB_SHIFTED(s, c, at, held, same, 4, 3));
#endif
#if K > 5
        imageStore(u_s5, p, KB_SHIFTED(s, c, at, held, same, 5, 4));
#endif
#if K > 6
        imageStore(u_s6, p, KB_SHIFTED(s, c, at, held, same, 6, 5));
#endif
#if K > 7
        imageStore(u_s7, p, KB_SHIFTED(s, c, at, held, same, 7, 6));
#endif
    }
    endInvocationInterlockARB();
#else
    if (!keep) {
        discard;
    }
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
    int at = kb_place(s, eye_depth(z), cb, u_back_bias, u_peel_eps, same, held, merged);
#if COUNT
    // a fragment that goes nowhere writes its pixel's surfaces back as they are (KB_SHIFTED
    // keeps them all for at == K): on llvmpipe a discard saves nothing, it only masks the lanes
    vec4 count = o_count;
    float kept = at == K ? count.r : float(min(held, K)) / 255.0;
    float let_go = count.g * 255.0 + (held > K && !merged ? 1.0 : 0.0);
    o_count = vec4(kept, min(let_go, 255.0) / 255.0, 0.0, 0.0);
#else
    if (at == K) {
        discard;
    }
#endif
    o_s0 = KB_SHIFTED(s, c, at, held, same, 0, 0);
#if K > 1
    o_s1 = KB_SHIFTED(s, c, at, held, same, 1, 0);
#endif
#if K > 2
    o_s2 = KB_SHIFTED(s, c, at, held, same, 2, 1);
#endif
#if K > 3
    o_s3 = KB_SHIFTED(s, c, at, held, same, 3, 2);
#endif
#if K > 4
    o_s4 = KB_SHIFTED(s, c, at, held, same, 4, 3);
#endif
#if K > 5
    o_s5 = KB_SHIFTED(s, c, at, held, same, 5, 4);
#endif
#if K > 6
    o_s6 = KB_SHIFTED(s, c, at, held, same, 6, 5);
#endif
#if K > 7
    o_s7 = KB_SHIFTED(s, c, at, held, same, 7, 6);
#endif
#endif
}

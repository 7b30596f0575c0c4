// Depth peeling: layer 0 is an ordinary depth test; layer i keeps only fragments behind layer
// i-1 by more than u_peel_eps in eye depth, so coplanar and duplicate faces peel as one surface.
// Coverage lives in the depth attachment (1.0: nothing), so only depth is cleared per layer.
#include "depth.glsl"
#include "fragment_depth.glsl"

uniform sampler2D u_prev_depth;
uniform bool u_peel;
uniform float u_peel_eps;
uniform bool u_ortho;
uniform float u_back_bias;
#if SELECTED_ONLY
uniform isampler2D u_selected;  // 1 for each designated part (depth masking, highlight)
#endif

in vec3 v_eye;
in vec3 v_normal;
flat in int v_part;
flat in int v_first_face;  // the instance's (geometry.vert)

#if NORMALS
layout(location = 0) out vec4 o_normal;   // eye-space normal facing the viewer
layout(location = 1) out ivec2 o_ids;     // (face + 1, part + 1)
#else
layout(location = 0) out int o_face;      // face + 1 alone: the ID buffer of triangle-ID silhouettes
#endif

void main() {
    float z = fragment_depth();
    if (u_peel) {
        float prev = texelFetch(u_prev_depth, ivec2(gl_FragCoord.xy), 0).r;
        if (prev >= 1.0 || eye_depth(z) <= eye_depth(prev) + u_peel_eps) {
            discard;
        }
    }
    vec3 n = normalize(v_normal);
    vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -v_eye;
    // two-sided: open meshes and inconsistent winding show the side that faces us
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
#if BACK_BIAS_IN_SHADER
    // the single-draw form of the renderer's back-face offset (see BACK_OFFSET there)
    gl_FragDepth = gl_FrontFacing ? z : min(z + u_back_bias, 1.0);
#elif EXACT_DEPTH
    gl_FragDepth = z;
#endif
#if FACE_IDS
    int face = v_first_face + gl_PrimitiveID;
#else
    int face = -1;
#endif
    int part = v_part;
#if SELECTED_ONLY
    if (texelFetch(u_selected, ivec2(part, 0), 0).r == 0) {
        discard;
    }
#endif
#if NORMALS
    o_normal = vec4(n, 1.0);
    o_ids = ivec2(face + 1, part + 1);
#else
    o_face = face + 1;
#endif
}

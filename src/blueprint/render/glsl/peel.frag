// Depth peeling: layer 0 is an ordinary depth test; layer i keeps only fragments behind layer
// i-1 by more than u_peel_eps in eye depth, so coplanar and duplicate faces peel as one surface.
#include "depth.glsl"

uniform sampler2D u_prev_depth;
uniform bool u_peel;
uniform float u_peel_eps;
uniform bool u_ortho;
uniform float u_back_bias;

in vec3 v_eye;
in vec3 v_normal;
flat in ivec2 v_ids;

layout(location = 0) out float o_depth;   // window depth, 0 where nothing was drawn
layout(location = 1) out vec4 o_normal;   // eye-space normal facing the viewer, w = 1
layout(location = 2) out ivec2 o_ids;     // (face + 1, part + 1), 0 where nothing was drawn

void main() {
    float z = gl_FragCoord.z;
    if (u_peel) {
        float prev = texelFetch(u_prev_depth, ivec2(gl_FragCoord.xy), 0).r;
        if (prev <= 0.0 || eye_depth(z) <= eye_depth(prev) + u_peel_eps) {
            discard;
        }
    }
    vec3 n = normalize(v_normal);
    vec3 to_eye = u_ortho ? vec3(0.0, 0.0, 1.0) : -v_eye;
    // two-sided: open meshes and inconsistent winding show the side that faces us
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    // Touching solids have coincident faces of opposite winding (the top of one, the bottom of
    // the other): a tiny push of back faces makes the front face win every pixel of the tie,
    // instead of whichever rounds nearer (speckle). Far below u_peel_eps, so both still peel
    // as one surface.
    gl_FragDepth = gl_FrontFacing ? z : min(z + u_back_bias, 1.0);
    o_depth = max(z, 1e-7);
    o_normal = vec4(n, 1.0);
    o_ids = v_ids + 1;
}

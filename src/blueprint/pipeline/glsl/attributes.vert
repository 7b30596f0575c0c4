// Attribute pass: the attributes the renderer's G-buffer lacks, drawn after each peeled layer.
// gl_Position is computed exactly as the peel's geometry.vert does, so both rasterise alike.
#include "instance.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;

out vec3 v_model;
out vec3 v_eye;
flat out vec3 v_normal;
flat out int v_first_face;
#if EXACT_DEPTH
out vec3 v_clip;  // fragment_depth.glsl
#endif

void main() {
    v_model = placed_position();
    vec4 eye = u_view * vec4(v_model, 1.0);
    v_eye = eye.xyz;
    v_normal = placed_normal();
    v_first_face = first_face();
    gl_Position = u_projection * eye;
#if EXACT_DEPTH
    v_clip = gl_Position.xyw;
#endif
}

// Attribute pass: the attributes the renderer's G-buffer lacks, drawn after each peeled layer.
// gl_Position is computed exactly as the peel's geometry.vert does, so both rasterise alike.
uniform mat4 u_view;
uniform mat4 u_projection;

in vec3 in_position;
in vec3 in_normal;

out vec3 v_model;
out vec3 v_eye;
flat out vec3 v_normal;
#if EXACT_DEPTH
out vec3 v_clip;  // fragment_depth.glsl
#endif

void main() {
    vec4 eye = u_view * vec4(in_position, 1.0);
    v_eye = eye.xyz;
    v_model = in_position;
    v_normal = in_normal;
    gl_Position = u_projection * eye;
#if EXACT_DEPTH
    v_clip = gl_Position.xyw;
#endif
}

// Geometry pass of the G-buffer: eye-space position and normal, and the part (no vertex is
// shared between parts). Face IDs come from gl_PrimitiveID in the fragment shader, so
// vertices are shared (indexed drawing).
uniform mat4 u_view;
uniform mat4 u_projection;

in vec3 in_position;
in vec3 in_normal;
in int in_part;

out vec3 v_eye;
out vec3 v_normal;
flat out int v_part;
#if EXACT_DEPTH
out vec3 v_clip;  // fragment_depth.glsl
#endif

void main() {
    vec4 eye = u_view * vec4(in_position, 1.0);
    v_eye = eye.xyz;
    // the view matrix is a rotation plus a translation, so its upper 3x3 maps normals
    v_normal = mat3(u_view) * in_normal;
    v_part = in_part;
    gl_Position = u_projection * eye;
#if EXACT_DEPTH
    v_clip = gl_Position.xyw;
#endif
}

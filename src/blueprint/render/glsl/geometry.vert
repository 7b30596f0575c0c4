// Geometry pass of the G-buffer: eye-space position and normal, the part (no vertex is shared
// between parts) and the first face of the vertex's instance (instance.glsl). Face IDs are
// that first face plus gl_PrimitiveID, which starts again at 0 for each instance drawn, so
// vertices are shared (indexed drawing) and a mesh is drawn once per instance.
#include "instance.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;

out vec3 v_eye;
out vec3 v_normal;
flat out int v_part;
flat out int v_first_face;
#if EXACT_DEPTH
out vec3 v_clip;  // fragment_depth.glsl
#endif

void main() {
    vec4 eye = u_view * vec4(placed_position(), 1.0);
    v_eye = eye.xyz;
    // the view matrix is a rotation plus a translation, so its upper 3x3 maps normals
    v_normal = mat3(u_view) * placed_normal();
    v_part = placed_part();
    v_first_face = first_face();
    gl_Position = u_projection * eye;
#if EXACT_DEPTH
    v_clip = gl_Position.xyw;
#endif
}

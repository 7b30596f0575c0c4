// geometry.vert with every corner snapped to a grid of 1/256 px before the rasteriser sees it:
// on any driver, a rasteriser that takes depth from the plane through snapped corners, as the
// H200's does. v_clip keeps the corner as projected, as the GPU's own snapping leaves it.
#include "instance.glsl"
const float SNAP = 256.0;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec2 u_target;

out vec3 v_eye;
out vec3 v_normal;
flat out int v_part;
flat out int v_first_face;
#if EXACT_DEPTH
out vec3 v_clip;
#endif

void main() {
    vec4 eye = u_view * vec4(placed_position(), 1.0);
    v_eye = eye.xyz;
    v_normal = mat3(u_view) * placed_normal();
    v_part = placed_part();
    v_first_face = first_face();
    vec4 clip = u_projection * eye;
#if EXACT_DEPTH
    v_clip = clip.xyw;
#endif
    vec2 window = u_target * (0.5 + 0.5 * clip.xy / clip.w);
    window = round(window * SNAP) / SNAP;
    gl_Position = vec4((window / u_target * 2.0 - 1.0) * clip.w, clip.zw);
}

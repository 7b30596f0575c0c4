// Triangle-ID silhouettes of one layer, list adjacency, as a full-screen pass (OpenGL 3.3).
#include "idsil_list.glsl"
#include "idsil_pixel.glsl"

out vec4 o_edge;

void main() {
    o_edge = vec4(idsil_value(ivec2(gl_FragCoord.xy)));
}

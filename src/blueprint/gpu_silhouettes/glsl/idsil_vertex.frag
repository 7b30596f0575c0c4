// Triangle-ID silhouettes of one layer, vertex adjacency, as a full-screen pass (OpenGL 3.3).
#include "blueprint.ops:glsl/idsil_vertex.glsl"
#include "idsil_pixel.glsl"

out vec4 o_edge;

void main() {
    o_edge = vec4(idsil_value(ivec2(gl_FragCoord.xy)));
}

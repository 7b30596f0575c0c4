// Edge map of one layer as a full-screen pass (OpenGL 3.3 path).
#include "edges.glsl"

uniform int u_layer;

out vec4 o_edge;

void main() {
    o_edge = vec4(layer_edge_value(ivec2(gl_FragCoord.xy), u_layer));
}

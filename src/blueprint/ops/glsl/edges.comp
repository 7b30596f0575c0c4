// Edge map of one layer into one slice of the edge array (OpenGL 4.3 path: compute runs on
// every shader core, where GPUs built for compute have few that rasterise).
layout(local_size_x = 8, local_size_y = 8) in;
#include "edges.glsl"

layout(r8, binding = 1) uniform writeonly image2DArray u_out;  // set by binding: moderngl cannot set image-array uniforms
uniform int u_layer;        // the slice
uniform int u_first_layer;  // the depth layer of slice 0

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThan(p, textureSize(u_depth, 0) - 1))) {
        return;
    }
    imageStore(u_out, ivec3(p, u_layer), vec4(layer_edge_value(p, u_first_layer + u_layer)));
}

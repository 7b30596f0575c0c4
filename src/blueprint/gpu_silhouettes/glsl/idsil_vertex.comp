// Triangle-ID silhouettes of one layer, vertex adjacency, into one slice of an r8 array
// (OpenGL 4.3 path); corner positions come straight from the buffer the ID pass drew.
layout(local_size_x = 8, local_size_y = 8) in;
#define IDSIL_CORNERS_SSBO
#include "blueprint.ops:glsl/idsil_vertex.glsl"
#include "idsil_pixel.glsl"

layout(r8, binding = 1) uniform writeonly image2DArray u_out;  // set by binding: moderngl cannot set image-array uniforms
uniform int u_layer;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThan(p, textureSize(u_depth, 0) - 1))) {
        return;
    }
    imageStore(u_out, ivec3(p, u_layer), vec4(idsil_value(p)));
}

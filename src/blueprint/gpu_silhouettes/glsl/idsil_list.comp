// Triangle-ID silhouettes of one layer, ID-list adjacency, into one slice of an r8 array
// (OpenGL 4.3 path).
layout(local_size_x = 8, local_size_y = 8) in;
#include "idsil_list.glsl"
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

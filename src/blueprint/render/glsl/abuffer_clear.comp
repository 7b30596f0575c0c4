// Empties every pixel's list and the totals before an A-buffer's geometry pass.
layout(local_size_x = 8, local_size_y = 8) in;
#include "abuffer.glsl"

layout(binding = 0, r32ui) writeonly uniform uimage2D u_head;
uniform uint u_capacity;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p == ivec2(0)) {
        drawn = 0u;
        capacity = u_capacity;
        long_lists = 0u;
        pairs = 0u;
        for (int i = 0; i <= MOST_LAYERS; ++i) {
            pixels_with[i] = 0u;
        }
    }
    if (all(lessThan(p, imageSize(u_head)))) {
        imageStore(u_head, p, uvec4(0u));
    }
}

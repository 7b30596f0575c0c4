// Grey-scale dilation by a disc, every slice of an edge array in one dispatch, an invocation a
// pixel of all its slices (a GPU pays per invocation more than per byte for an r8 array);
// narrower (fainter) lines on hidden layers (_widths.glsl).
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
#include "_widths.glsl"

uniform sampler2DArray u_source;
layout(r8, binding = 1) uniform writeonly image2DArray u_out;  // set by binding: moderngl cannot set image-array uniforms
uniform int u_layer;   // the depth layer of slice 0
uniform int u_slices;  // slices holding layers

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 last = textureSize(u_source, 0).xy - 1;
    if (any(greaterThan(p, last))) {
        return;
    }
    for (int z = 0; z < u_slices; ++z) {
        vec2 width = layer_width(u_layer + z);
        int r = int(ceil(width.x));
        float v = 0.0;
        for (int dy = -r; dy <= r; ++dy) {
            for (int dx = -r; dx <= r; ++dx) {
                float weight = clamp(width.x + 1.0 - length(vec2(dx, dy)), 0.0, 1.0);
                ivec2 q = clamp(p + ivec2(dx, dy), ivec2(0), last);
                v = max(v, weight * texelFetch(u_source, ivec3(q, z), 0).r);
            }
        }
        imageStore(u_out, ivec3(p, z), vec4(v * width.y));
    }
}

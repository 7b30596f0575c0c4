// Depth masking: passes (and is counted by an occlusion query) where the designated parts'
// front surface is already among the layers peeled, i.e. where this layer lies at or behind
// it, or is empty. With u_count_all it counts every pixel the designated parts cover.
#include "depth.glsl"

uniform sampler2D u_mask_depth;   // front depth of the designated parts, 1.0 where none
uniform sampler2D u_layer_depth;  // depth of the layer just peeled
uniform bool u_count_all;
uniform float u_peel_eps;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float mask = texelFetch(u_mask_depth, p, 0).r;
    if (mask >= 1.0) {
        discard;
    }
    if (!u_count_all) {
        float z = texelFetch(u_layer_depth, p, 0).r;
        if (z < 1.0 && eye_depth(z) < eye_depth(mask) - u_peel_eps) {
            discard;
        }
    }
}

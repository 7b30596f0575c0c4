// One layer of the k-buffer into the G-buffer, as the peel would have drawn it: its depth
// (biased for back faces), normal and IDs; nothing where the layer has no surface. A pixel's
// targets hold surfaces only up to the first empty one (kbuffer.frag), so a layer is read only
// where the one before it has a surface.
#extension GL_ARB_shading_language_packing : require
#include "kbuffer.glsl"

uniform usampler2D u_surfaces;
uniform float u_back_bias;
uniform sampler2D u_prev_depth;
uniform bool u_first;  // the first layer of a pass: its target was cleared

layout(location = 0) out vec4 o_normal;
layout(location = 1) out ivec2 o_ids;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uvec4 s = texelFetch(u_surfaces, p, 0);
    if (kb_empty(s) || (!u_first && texelFetch(u_prev_depth, p, 0).r >= 1.0)) {
        discard;
    }
    gl_FragDepth = kb_depth(s, u_back_bias);
    o_normal = vec4(kb_normal(s), 1.0);
    o_ids = kb_ids(s);
}

// Coverage of one silhouette segment at a pixel, as blueprint.silhouette.draw_segments computes
// it on the CPU (u_reach minus the distance to the segment, at most 1), kept in the layer of the
// surfaces it lies on: layer k holds the edges behind exactly k surfaces. An edge counts as on a
// layer's surface where it is no farther than that layer's farthest depth among the 3x3 pixels
// around (the empty background as infinitely far), plus u_margin: a silhouette lies where the
// surface turns away, so the pixels beside it see past it, or a surface in front of it.
// With u_split the pass also draws, into its second target, every edge behind this layer: the
// last layer asked for, which needs no peel of its own.
#include "depth.glsl"

uniform sampler2D u_layer_depth;  // this layer's window depth, 1.0 where empty
uniform sampler2D u_front_depth;  // the layer before's (unused on layer 0)
uniform bool u_first;             // layer 0: nothing in front to be behind
uniform bool u_split;             // edges behind this layer go to the second target
uniform float u_reach;
uniform float u_margin;           // eye-depth tolerance

flat in vec4 g_ends;
flat in vec2 g_depth;

layout(location = 0) out vec4 o_edge;
layout(location = 1) out vec4 o_behind;

float farthest(sampler2D depth, ivec2 p) {
    ivec2 last = textureSize(depth, 0) - 1;
    float z = 0.0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            z = max(z, texelFetch(depth, clamp(p + ivec2(dx, dy), ivec2(0), last), 0).r);
        }
    }
    return z < 1.0 ? eye_depth(z) : 1e30;
}

void main() {
    vec2 p = gl_FragCoord.xy;
    vec2 a = g_ends.xy;
    vec2 d = g_ends.zw - a;
    float len2 = dot(d, d);
    float t = len2 > 0.0 ? clamp(dot(p - a, d) / len2, 0.0, 1.0) : 0.0;
    float coverage = min(u_reach - length(p - a - t * d), 1.0);
    if (coverage <= 0.0) {
        discard;
    }
    // window depth is linear along a projected segment, so it interpolates in pixels
    float z = eye_depth(mix(g_depth.x, g_depth.y, t));
    ivec2 pixel = ivec2(p);
    if (!u_first && z <= farthest(u_front_depth, pixel) + u_margin) {
        discard;  // on a surface of a layer in front
    }
    bool behind = z > farthest(u_layer_depth, pixel) + u_margin;
    if (behind && !u_split) {
        discard;
    }
    o_edge = vec4(behind ? 0.0 : coverage);
    o_behind = vec4(behind ? coverage : 0.0);
}

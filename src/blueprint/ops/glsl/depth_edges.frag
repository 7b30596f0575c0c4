// Depth edges: 1 where the second difference of depth along x or y exceeds u_threshold.
// Window depth is affine in screen space on any plane, so planes give 0 and jumps give edges.
// Along an axis at the image's border the difference is 0 (the frame draws no line).
#include "_fetch.glsl"

uniform sampler2D u_depth;
uniform float u_threshold;

out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(u_depth, 0) - 1;
    float c = 2.0 * fetch(u_depth, p).r;
    float dx = abs(fetch(u_depth, p + ivec2(-1, 0)).r + fetch(u_depth, p + ivec2(1, 0)).r - c);
    float dy = abs(fetch(u_depth, p + ivec2(0, -1)).r + fetch(u_depth, p + ivec2(0, 1)).r - c);
    dx = p.x > 0 && p.x < last.x ? dx : 0.0;
    dy = p.y > 0 && p.y < last.y ? dy : 0.0;
    float e = float(max(dx, dy) > u_threshold);
    o_value = vec4(e, e, e, 1.0);
}

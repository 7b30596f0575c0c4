// Layers left behind a capped peel: every fragment behind the last layer peeled (by more than
// the peel's tolerance, as peel.frag decides) adds one to its pixel, so the most any pixel holds
// is how many more layers a peel without the cap would draw (coincident surfaces, which the
// peel takes as one, count apart: an upper bound).
#include "depth.glsl"
#include "fragment_depth.glsl"

uniform sampler2D u_prev_depth;
uniform float u_peel_eps;

layout(location = 0) out vec4 o_count;

void main() {
    float z = fragment_depth();
    float prev = texelFetch(u_prev_depth, ivec2(gl_FragCoord.xy), 0).r;
    if (prev >= 1.0 || eye_depth(z) <= eye_depth(prev) + u_peel_eps) {
        discard;
    }
    o_count = vec4(1.0);
}

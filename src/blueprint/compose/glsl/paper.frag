#include "paper.glsl"

out vec4 o_color;

void main() {
    o_color = paper_color(gl_FragCoord.xy);
}

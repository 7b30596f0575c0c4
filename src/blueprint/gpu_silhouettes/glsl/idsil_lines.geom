// A drawn edge's segment (idsil_lines.vert) as a rectangle around the capsule of radius u_reach
// about it, for the fragment shader's anti-aliased coverage; edges not drawn emit nothing.
layout(points) in;
layout(triangle_strip, max_vertices = 4) out;

uniform vec2 u_size;    // viewport in pixels
uniform float u_reach;  // coverage falls to 0 this far from the segment, in pixels

in vec4 v_ends[];
in vec2 v_depth[];
in float v_drawn[];

flat out vec4 g_ends;
flat out vec2 g_depth;

void main() {
    if (v_drawn[0] < 0.5) {
        return;
    }
    vec2 a = v_ends[0].xy;
    vec2 b = v_ends[0].zw;
    vec2 d = b - a;
    vec2 along = dot(d, d) > 0.0 ? normalize(d) : vec2(1.0, 0.0);
    vec2 across = vec2(-along.y, along.x);
    float reach = u_reach + 0.01;
    for (int k = 0; k < 4; ++k) {
        vec2 p = ((k < 2) ? a - along * reach : b + along * reach) + across * ((k % 2 == 0) ? -reach : reach);
        g_ends = v_ends[0];
        g_depth = v_depth[0];
        gl_Position = vec4(p / u_size * 2.0 - 1.0, 0.0, 1.0);
        EmitVertex();
    }
    EndPrimitive();
}

// Normal edges: 1 at a covered pixel whose normal turns more than the crease angle from a
// covered 4-neighbour's (dot below u_cos); 0 elsewhere. Coverage comes from window depth.
uniform sampler2D u_normal;
uniform sampler2D u_depth;
uniform float u_cos;

out vec4 o_value;

const ivec2 OFFSETS[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(u_depth, 0) - 1;
    float e = 0.0;
    if (texelFetch(u_depth, p, 0).r < 1.0) {
        vec3 n = normalize(texelFetch(u_normal, p, 0).xyz);
        for (int i = 0; i < 4; ++i) {
            ivec2 q = clamp(p + OFFSETS[i], ivec2(0), last);
            if (texelFetch(u_depth, q, 0).r < 1.0 && dot(n, normalize(texelFetch(u_normal, q, 0).xyz)) < u_cos) {
                e = 1.0;
            }
        }
    }
    o_value = vec4(e, e, e, 1.0);
}

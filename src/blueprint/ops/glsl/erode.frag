// Grey-scale erosion by a disc with a soft rim: the dual of dilate (1 - dilate(1 - x)).
uniform sampler2D u_source;
uniform float u_radius;

out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(u_source, 0) - 1;
    int r = int(ceil(u_radius));
    float v = 1.0;
    for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
            float weight = clamp(u_radius + 1.0 - length(vec2(dx, dy)), 0.0, 1.0);
            ivec2 q = clamp(p + ivec2(dx, dy), ivec2(0), last);
            v = min(v, 1.0 - weight * (1.0 - texelFetch(u_source, q, 0).r));
        }
    }
    o_value = vec4(v);
}

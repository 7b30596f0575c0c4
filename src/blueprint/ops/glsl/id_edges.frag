// ID edges: 1 where a 4-neighbour (edge clamped) holds another ID in channel u_channel.
uniform isampler2D u_ids;
uniform int u_channel;

out vec4 o_value;

const ivec2 OFFSETS[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(u_ids, 0) - 1;
    int id = texelFetch(u_ids, p, 0)[u_channel];
    float e = 0.0;
    for (int i = 0; i < 4; ++i) {
        if (texelFetch(u_ids, clamp(p + OFFSETS[i], ivec2(0), last), 0)[u_channel] != id) {
            e = 1.0;
        }
    }
    o_value = vec4(e, e, e, 1.0);
}

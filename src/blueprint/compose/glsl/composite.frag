// Depth-sprite composite of up to 8 layer maps (one texture each), back to front, each
// weighted by its ink's opacity; at each sample the strongest line wins (lines.glsl), and a box
// filter over each LAYERS_FACTOR^2 block gives anti-aliased lines. Premultiplied output,
// blended over what is there (the paper and farther groups). With SHADED, the shaded parts'
// colour goes in at each sample just behind the edges of the layer their surface belongs to
// (shaded_layers.glsl). The same arithmetic as compose.comp, the compute form.
uniform sampler2D u_layers0;
uniform sampler2D u_layers1;
uniform sampler2D u_layers2;
uniform sampler2D u_layers3;
uniform sampler2D u_layers4;
uniform sampler2D u_layers5;
uniform sampler2D u_layers6;
uniform sampler2D u_layers7;
// Defines: LAYERS_FACTOR, input pixels per output pixel along each axis; COUNT, the layers of
// this group (a constant, since a software rasteriser fetches every layer a branch on a
// uniform skips).
uniform bool u_threshold;     // wire-frame variant: binary edges
uniform vec4 u_ink[COUNT];    // straight colour and opacity per layer of the group

out vec4 o_value;

#include "lines.glsl"

float edge_at(int k, ivec2 q) {
    float e;
    if (k == 0) e = texelFetch(u_layers0, q, 0).r;
    else if (k == 1) e = texelFetch(u_layers1, q, 0).r;
    else if (k == 2) e = texelFetch(u_layers2, q, 0).r;
    else if (k == 3) e = texelFetch(u_layers3, q, 0).r;
    else if (k == 4) e = texelFetch(u_layers4, q, 0).r;
    else if (k == 5) e = texelFetch(u_layers5, q, 0).r;
    else if (k == 6) e = texelFetch(u_layers6, q, 0).r;
    else e = texelFetch(u_layers7, q, 0).r;
    return u_threshold ? step(0.5, e) : e;
}

#if SHADED
#include "shaded_layers.glsl"

void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * LAYERS_FACTOR;
    vec4 sum = vec4(0.0);
    for (int y = 0; y < LAYERS_FACTOR; ++y) {
        for (int x = 0; x < LAYERS_FACTOR; ++x) {
            vec4 sample_color;
            SHADED_COMPOSITE(edge_at, COUNT, u_ink, base + ivec2(x, y), sample_color)
            sum += sample_color;
        }
    }
    o_value = sum / float(LAYERS_FACTOR * LAYERS_FACTOR);
}
#else
void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * LAYERS_FACTOR;
    vec4 lines = vec4(0.0);
    for (int y = 0; y < LAYERS_FACTOR; ++y) {
        for (int x = 0; x < LAYERS_FACTOR; ++x) {
            vec4 union_ = vec4(0.0);
            for (int k = 7; k >= 0; --k) {
                if (k < COUNT) {
                    float a = clamp(edge_at(k, base + ivec2(x, y)), 0.0, 1.0) * u_ink[k].a;
                    union_ = strongest(union_, u_ink[k].rgb, a);
                }
            }
            lines += union_;
        }
    }
    o_value = lines / float(LAYERS_FACTOR * LAYERS_FACTOR);
}
#endif

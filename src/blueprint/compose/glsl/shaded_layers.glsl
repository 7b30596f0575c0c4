// Per-sample composition with shaded parts: at each supersample, layers are composed back to
// front and the shading goes in just behind the edges of the layer its surface belongs to, so
// edges in front of a shaded part stay on top and (opaque) shading hides the ones behind. Lines
// between two shaded surfaces unite by the strongest (lines.glsl) and go over what is behind
// them when the next shading (or the end) comes.
uniform sampler2D u_shade_index;  // r8: 1 + layer of the shaded surface, 0 where none
uniform sampler2D u_shade_color;  // premultiplied
uniform int u_first_layer;        // global index of this pass's first layer

vec4 over(vec4 top, vec4 below) {
    return top + below * (1.0 - top.a);
}

// ``edge(k, q)`` returns layer k's edge intensity at supersample q; ``count`` layers take part
#define SHADED_COMPOSITE(edge, count, ink, q, result)                                    \
    {                                                                                    \
        int shaded = int(texelFetch(u_shade_index, q, 0).r * 255.0 + 0.5) - 1 - u_first_layer; \
        result = vec4(0.0);                                                              \
        vec4 lines = vec4(0.0);                                                          \
        for (int k = 7; k >= 0; --k) {                                                   \
            if (k < count) {                                                             \
                if (k == shaded) {                                                       \
                    result = over(texelFetch(u_shade_color, q, 0), over(lines, result)); \
                    lines = vec4(0.0);                                                   \
                }                                                                        \
                lines = strongest(lines, ink[k].rgb, clamp(edge(k, q), 0.0, 1.0) * ink[k].a); \
            }                                                                            \
        }                                                                                \
        result = over(lines, result);                                                    \
    }

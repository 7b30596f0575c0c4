// The composite (composite.frag, one sample a pixel, no shading) of a batch of BATCH layers'
// edge values, for an edges pass that composes the layers where it finds them instead of
// writing a map a layer for the composite to read: each value rounded as a layer's r8 map
// stores it and read back as the composite reads it, the layers taken back to front, so the
// colour is the composite's to the bit. Drawn blended over the paper as the composite's sprites
// are (compositor.Compositor.composed_in_place).
#include "lines.glsl"

uniform bool u_threshold;  // wire-frame variant: binary edges
uniform vec4 u_ink[BATCH];  // straight colour and opacity per layer of the batch, 0 past its layers

layout(location = 0) out vec4 o_value;

// An edge value as an r8 target stores it and a fetch reads it back (llvmpipe rounds to nearest
// even and multiplies by the reciprocal: checked over every float in [0, 1] tried)
float stored_edge(float e) {
    return roundEven(clamp(e, 0.0, 1.0) * 255.0) * (1.0 / 255.0);
}

vec4 compose_batch(float e[BATCH]) {
    vec4 union_ = vec4(0.0);
    for (int k = BATCH - 1; k >= 0; --k) {
        float v = stored_edge(e[k]);
        v = u_threshold ? step(0.5, v) : v;
        union_ = strongest(union_, u_ink[k].rgb, clamp(v, 0.0, 1.0) * u_ink[k].a);
    }
    return union_;
}

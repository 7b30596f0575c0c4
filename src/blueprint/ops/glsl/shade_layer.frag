// Marks where the shaded parts' front surface is the layer just peeled: writes 1 + the layer
// index (and discards elsewhere, so the target accumulates every layer), for composition to put
// the shading between that layer's edges and the ones behind.
#include "depth.glsl"

uniform sampler2D u_surface;  // front depth of the shaded parts
uniform sampler2D u_depth;    // depth of this layer
uniform float u_peel_eps;
uniform int u_layer;

out vec4 o_index;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float s = texelFetch(u_surface, p, 0).r;
    float z = texelFetch(u_depth, p, 0).r;
    if (s >= 1.0 || z >= 1.0 || abs(eye_depth(z) - eye_depth(s)) > u_peel_eps) {
        discard;
    }
    o_index = vec4(float(u_layer + 1) / 255.0);
}

// The faces of the first u_layers layers at a list of pixels, read from the A-buffer's sorted
// lists in place (abuffer.glsl) instead of each layer unpacked into the G-buffer and read back
// whole: face + 1 of layer l at pixel i into faces[l * u_count + i], 0 past the pixel's last
// layer. A vector drawing's occlusion probes a small share of the picture's pixels.
#extension GL_ARB_shading_language_packing : require
layout(local_size_x = 64) in;
#include "kbuffer.glsl"
#include "abuffer.glsl"

layout(binding = 1, r32ui) readonly uniform uimage2D u_cursor;  // each pixel's layer 0 (the resolve's)
layout(std430, binding = 5) readonly buffer Pixels {
    uint pixels[];  // flat indices y * width + x, OpenGL rows (bottom up)
};
layout(std430, binding = 6) writeonly buffer Faces {
    uint faces[];
};
uniform int u_count;
uniform int u_layers;

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= uint(u_count)) {
        return;
    }
    uint width = uint(imageSize(u_cursor).x);
    uint at = imageLoad(u_cursor, ivec2(int(pixels[i] % width), int(pixels[i] / width))).x;
    for (int layer = 0; layer < u_layers; ++layer) {
        uint face = 0u;
        if (at != 0u) {
            face = uint(kb_ids(AB_NODE(at - 1u)).x);
            at = AB_ORDER(at - 1u);
        }
        faces[uint(layer) * uint(u_count) + i] = face;
    }
}

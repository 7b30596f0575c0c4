// One peeled layer's faces into a texture of their own, for occlusion.comp (LAYERED): face + 1
// where the layer has a surface, 0 where its depth is 1 (none).
layout(local_size_x = 8, local_size_y = 8) in;

uniform isampler2D u_ids;
uniform sampler2D u_depth;
uniform ivec2 u_size;
layout(r32i, binding = 7) writeonly uniform iimage2D u_out;

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, u_size))) return;
    int face = texelFetch(u_depth, q, 0).r < 1.0 ? texelFetch(u_ids, q, 0).r : 0;
    imageStore(u_out, q, ivec4(face));
}

// Pixels with at least k + 1 surfaces in the faces k-buffer (see occlusion.comp), for k < K:
// what the peel's stop rules count, without reading the layers back.
layout(local_size_x = 8, local_size_y = 8) in;

uniform usampler2D u_s0;
#if K > 1
uniform usampler2D u_s1;
#endif
#if K > 2
uniform usampler2D u_s2;
#endif
#if K > 3
uniform usampler2D u_s3;
#endif
#if K > 4
uniform usampler2D u_s4;
#endif
#if K > 5
uniform usampler2D u_s5;
#endif
#if K > 6
uniform usampler2D u_s6;
#endif
#if K > 7
uniform usampler2D u_s7;
#endif
uniform ivec2 u_size;
layout(std430, binding = 3) buffer Counts { uint counts[]; };

shared uint group_counts[K];

uint surfaces(ivec2 q) {
    if (texelFetch(u_s0, q, 0).y == 0u) return 0u;
#if K > 1
    if (texelFetch(u_s1, q, 0).y == 0u) return 1u;
#endif
#if K > 2
    if (texelFetch(u_s2, q, 0).y == 0u) return 2u;
#endif
#if K > 3
    if (texelFetch(u_s3, q, 0).y == 0u) return 3u;
#endif
#if K > 4
    if (texelFetch(u_s4, q, 0).y == 0u) return 4u;
#endif
#if K > 5
    if (texelFetch(u_s5, q, 0).y == 0u) return 5u;
#endif
#if K > 6
    if (texelFetch(u_s6, q, 0).y == 0u) return 6u;
#endif
#if K > 7
    if (texelFetch(u_s7, q, 0).y == 0u) return 7u;
#endif
    return uint(K);
}

void main() {
    uint local = gl_LocalInvocationIndex;
    if (local < uint(K)) group_counts[local] = 0u;
    barrier();
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (all(lessThan(q, u_size))) {
        uint n = surfaces(q);
        for (uint k = 0u; k < n; ++k) atomicAdd(group_counts[k], 1u);
    }
    barrier();
    if (local < uint(K) && group_counts[local] > 0u) atomicAdd(counts[local], group_counts[local]);
}

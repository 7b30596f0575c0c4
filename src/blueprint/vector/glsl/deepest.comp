// The most surfaces any pixel has in the faces k-buffer (see occlusion.comp): what the peel's
// stop rules count where no layer has to cover a fraction of the first (layer_counts.comp
// counts every layer's pixels for those). The layers' pixel counts fall from layer to layer,
// so the first empty layer is the deepest pixel's surface count. A pixel looks at its
// surface as deep as the deepest found so far first, and an invocation's pixels after one
// with K surfaces are not looked at: mostly one texel a pixel, or none. Each invocation
// takes a column of ROWS pixels, as llvmpipe spends more on starting invocations than on
// looking at one texel.
#define ROWS 64  // gpu._DEEPEST_ROWS
layout(local_size_x = 64) in;

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
layout(std430, binding = 3) coherent buffer Deepest { uint deepest; };

// whether pixel q has a surface k
bool has(uint k, ivec2 q) {
    switch (k) {
    case 0u: return texelFetch(u_s0, q, 0).y != 0u;
#if K > 1
    case 1u: return texelFetch(u_s1, q, 0).y != 0u;
#endif
#if K > 2
    case 2u: return texelFetch(u_s2, q, 0).y != 0u;
#endif
#if K > 3
    case 3u: return texelFetch(u_s3, q, 0).y != 0u;
#endif
#if K > 4
    case 4u: return texelFetch(u_s4, q, 0).y != 0u;
#endif
#if K > 5
    case 5u: return texelFetch(u_s5, q, 0).y != 0u;
#endif
#if K > 6
    case 6u: return texelFetch(u_s6, q, 0).y != 0u;
#endif
#if K > 7
    case 7u: return texelFetch(u_s7, q, 0).y != 0u;
#endif
    }
    return false;
}

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= u_size.x) return;
    int top = int(gl_GlobalInvocationID.y) * ROWS;
    for (int y = top; y < min(u_size.y, top + ROWS); ++y) {
        ivec2 q = ivec2(x, y);
        uint found = deepest;
        if (found >= uint(K)) return;
        // an empty surface there ends the pixel's surfaces no deeper; one that is not may be
        // an older frame's, beyond the pixel's first empty one: counted from the top
        if (!has(found, q)) continue;
        uint n = 0u;
        while (n < uint(K) && has(n, q)) ++n;
        if (n > found) atomicMax(deepest, n);
    }
}

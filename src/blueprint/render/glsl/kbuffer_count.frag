// How many layers one k-buffer pass found at each pixel, for passes that read the layers
// straight from its surfaces instead of unpacked into the G-buffer: a pixel's surfaces are held
// from the first target on, and the first empty one ends them (targets after it keep whatever an
// earlier pass left). Written as count / 255 into an r8 target. (depth.glsl: kbuffer.glsl
// places fragments by eye depth once K is defined.)
#extension GL_ARB_shading_language_packing : require
#include "depth.glsl"
#include "kbuffer.glsl"

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

layout(location = 0) out vec4 o_count;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int count = 0;
#define KB_COUNT(s, k) if (count == (k) && !kb_empty(texelFetch(s, p, 0))) { count = (k) + 1; }
    KB_COUNT(u_s0, 0)
#if K > 1
    KB_COUNT(u_s1, 1)
#endif
#if K > 2
    KB_COUNT(u_s2, 2)
#endif
#if K > 3
    KB_COUNT(u_s3, 3)
#endif
#if K > 4
    KB_COUNT(u_s4, 4)
#endif
#if K > 5
    KB_COUNT(u_s5, 5)
#endif
#if K > 6
    KB_COUNT(u_s6, 6)
#endif
#if K > 7
    KB_COUNT(u_s7, 7)
#endif
    o_count = vec4(float(count) / 255.0);
}

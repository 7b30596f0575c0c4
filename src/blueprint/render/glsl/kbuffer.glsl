// One surface of the k-buffer in a uvec4: (window depth bits, with bit 31 set for a back face;
// the normal's x and y as halves; its z as a half in the low 16 bits and part + 1 in the high
// 16; face + 1). All zero where there is none: part + 1 is never 0. With WIDE_PARTS (a mesh of
// 0xFFFF parts or more) the normal is two 16-bit octahedral coordinates and part + 1 takes the
// third word whole. With IDS_ONLY a uvec2 of the depth bits and face + 1 (never 0 then: faces
// are always tracked).
const uint KB_BACK = 0x80000000u;

#ifndef IDS_ONLY
#define IDS_ONLY 0
#endif
#ifndef WIDE_PARTS
#define WIDE_PARTS 0
#endif

#if IDS_ONLY
#define KB_T uvec2

uvec2 kb_pack(float z, bool back, vec3 n, int face, int part) {
    return uvec2(floatBitsToUint(z) | (back ? KB_BACK : 0u), uint(face + 1));
}

bool kb_empty(uvec2 s) {
    return s.y == 0u;
}
#else
#define KB_T uvec4

// A unit vector's component as a half, rounded toward zero: how llvmpipe stores a float into
// the G-buffer's half-float normals (packHalf2x16 rounds to nearest), so both ways of peeling
// give the same bits. Magnitudes below the smallest normal half become zero.
uint kb_half(float v) {
    uint bits = floatBitsToUint(v);
    uint sign = (bits >> 16) & 0x8000u;
    int exponent = int((bits >> 23) & 0xffu) - 127 + 15;
    if (exponent <= 0) {
        return sign;
    }
    return sign | (uint(min(exponent, 30)) << 10) | ((bits >> 13) & 0x3ffu);
}

#if WIDE_PARTS
// A unit vector on the octahedron |x| + |y| + |z| = 1, its lower half folded over the upper,
// as two signed 16-bit coordinates: within 1e-4 of the vector, where the halves' x and y
// are within 5e-4 (kb_half), in the bits the part needs.
int kb_snorm(float v) {
    return int(round(clamp(v, -1.0, 1.0) * 32767.0));
}

vec2 kb_sign(vec2 v) {
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

uint kb_octahedral(vec3 n) {
    vec2 e = n.xy / max(abs(n.x) + abs(n.y) + abs(n.z), 1e-30);
    if (n.z < 0.0) {
        e = (1.0 - abs(e.yx)) * kb_sign(e);
    }
    return uint(kb_snorm(e.x) & 0xffff) | (uint(kb_snorm(e.y)) << 16);
}

vec3 kb_unoctahedral(uint bits) {
    vec2 e = vec2(float(int(bits << 16) >> 16), float(int(bits) >> 16)) / 32767.0;
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        n.xy = (1.0 - abs(n.yx)) * kb_sign(n.xy);
    }
    return normalize(n);
}

uvec4 kb_pack(float z, bool back, vec3 n, int face, int part) {
    return uvec4(floatBitsToUint(z) | (back ? KB_BACK : 0u), kb_octahedral(n), uint(part + 1), uint(face + 1));
}

bool kb_empty(uvec4 s) {
    return s.z == 0u;
}
#else
uvec4 kb_pack(float z, bool back, vec3 n, int face, int part) {
    return uvec4(
        floatBitsToUint(z) | (back ? KB_BACK : 0u),
        kb_half(n.x) | (kb_half(n.y) << 16),
        kb_half(n.z) | (uint(part + 1) << 16),
        uint(face + 1));
}

bool kb_empty(uvec4 s) {
    return s.z < 0x10000u;
}
#endif
#endif

float kb_raw(KB_T s) {
    return uintBitsToFloat(s.x & ~KB_BACK);
}

// the depth the peel writes: back faces pushed back by the bias (see BACK_OFFSET)
float kb_depth(KB_T s, float back_bias) {
    float z = kb_raw(s);
    return (s.x & KB_BACK) != 0u ? min(z + back_bias, 1.0) : z;
}

// A half of kb_half's (no subnormal, infinity or NaN) as a float, exactly, in integer steps,
// which llvmpipe runs faster than unpackHalf2x16.
float kb_unhalf(uint h) {
    uint magnitude = (h & 0x7fffu) == 0u ? 0u : ((h & 0x7fffu) << 13) + 0x38000000u;
    return uintBitsToFloat(((h & 0x8000u) << 16) | magnitude);
}

#if WIDE_PARTS
vec3 kb_normal(uvec4 s) {
    return kb_unoctahedral(s.y);
}

ivec2 kb_ids(uvec4 s) {
    return ivec2(int(s.w), int(s.z));
}
#else
vec3 kb_normal(uvec4 s) {
    return vec3(kb_unhalf(s.y & 0xffffu), kb_unhalf(s.y >> 16), kb_unhalf(s.z & 0xffffu));
}

ivec2 kb_ids(uvec4 s) {
    return ivec2(int(s.w), int(s.z >> 16));
}
#endif

#ifdef K
// Where a fragment ``c`` (biased depth ``cb``, eye depth of its raw depth ``ze``) goes among a
// pixel's held surfaces ``s``, by the rules of peel.frag: before the first surface it lies in
// front of (taking that surface's place when it lies within the tolerance behind: ``same``),
// or after them all; K where it is part of a held surface (``merged``) or behind all K.
// ``held`` is how many surfaces the pixel holds after it goes in (K + 1: one is let go).
int kb_place(
    KB_T s[K], float ze, float cb, float back_bias, float eps, out bool same, out int held, out bool merged
) {
    // The surfaces held come first, and the place after them is empty: only the first target
    // is cleared before a pass, the rest of a pixel's targets are read only up to there.
    int count = K;
    for (int k = 0; k < K; ++k) {
        if (count == K && kb_empty(s[k])) {
            count = k;
        }
    }
    // The surfaces are sorted by biased depth, so the first one the fragment lies in front of
    // is its place, and the one before that (the farthest it lies at or behind) is the only one
    // it may be part of: eye depth never decreases with window depth, so if it is within the
    // tolerance of any surface in front of it, it is within that of this one. One division
    // each instead of two a surface held (llvmpipe runs every branch of the loop).
    int at = count;
    float before = 0.0;  // the biased depth of the surface before ``at``
    float raw = 0.0;     // the raw depth of the surface at ``at``
    for (int k = 0; k < K; ++k) {
        float sb = kb_depth(s[k], back_bias);
        if (k < count && at == count) {
            if (cb >= sb) {
                before = sb;
            } else {
                at = k;
                raw = kb_raw(s[k]);
            }
        }
    }
    bool part_of_one = at > 0 && ze <= eye_depth(before) + eps;
    // in front of it: the peel would take this fragment first and then skip the surface if it
    // lies within the tolerance behind
    same = !part_of_one && at < count && eye_depth(raw) <= eye_depth(cb) + eps;
    held = same ? count : count + 1;
    merged = part_of_one;
    return part_of_one ? K : at;
}

// Surface k of the pixel once the fragment is placed (constant k only: llvmpipe miscompiled
// writes through a computed index); ``prev`` is k - 1 (0 for k = 0, where it is never read).
#define KB_SHIFTED(s, c, at, held, same, k, prev) \
    ((k) < (at) ? s[k] : ((k) == (at) ? (c) : ((k) < (held) ? ((same) ? s[k] : s[prev]) : KB_T(0u))))
#endif

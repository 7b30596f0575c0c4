// Occlusion level of every sample of a drawing's lines, from the faces k-buffer left on the
// GPU (kbuffer.frag with IDS_ONLY: surface k of a pixel in target k, face + 1 in .y, a pixel's
// surfaces running up to the first with face 0). The rules are those of
// vector/occlusion/levels.py, which is the reference: a surface is in front of a sample when
// the plane of its triangle meets the sample's view ray nearer to the eye by more than
// u_tolerance (eye depth); the line's own faces never count; the level is the minimum over the
// 2 x 2 pixels whose centres surround the sample, where off contours a pixel with no surface at
// all does not take part.
// For samples of mesh edges the surface seen at the line's depth a pixel to either side
// (surface number "how many there are in front" there) is written too, for the crease check.
// With LAYERED the faces come a layer a texture as peeled a pass a layer (copy_faces.comp:
// r32i, face + 1, 0 where none). With REMAP the faces k-buffer drew some faces alone, numbered
// from 0 (u_remap names each). With STACKS they come as read back at the pixels probed
// (levels.PixelLayers), any number of layers: u_where holds a pixel's first row of the u_faces
// table and its surface count.
#include "table.glsl"

layout(local_size_x = 64) in;

#if LAYERED
#define SAMPLER isampler2D
#define FACE1(S, q) texelFetch(S, q, 0).r
#else
#define SAMPLER usampler2D
#define FACE1(S, q) int(texelFetch(S, q, 0).y)
#endif

// pixels as the CPU reference floors them in double precision (a pixel coordinate a hair below
// a whole number rounds up to it in single precision)
struct Sample {
    vec3 eye;      // eye coordinates
    int flags;     // 1: off contours, 2: check the sides, 4: a smooth contour (u_reach)
    ivec4 pixel;   // the first of the 2 x 2 pixels around the sample x, y (pixels.around, y down);
                   // the pixel a step to one side of the line x, y
    ivec4 own;     // the pixel a step to the other side x, y; own faces (-1: none)
};

layout(std430, binding = 0) readonly buffer Samples { Sample samples[]; };
layout(std430, binding = 2) writeonly buffer Levels { ivec4 result[]; };  // level, side faces
uniform sampler2D u_planes;  // a table (gpu/tables.py) of the faces' planes n, c; last row: none

#if STACKS
uniform isampler2D u_where;  // (first row in u_faces, surfaces) of every pixel, OpenGL rows
uniform isampler2D u_faces;  // a table of the faces of every pixel's surfaces, front first
#else
uniform SAMPLER u_s0;
#endif
#if K > 1
uniform SAMPLER u_s1;
#endif
#if K > 2
uniform SAMPLER u_s2;
#endif
#if K > 3
uniform SAMPLER u_s3;
#endif
#if K > 4
uniform SAMPLER u_s4;
#endif
#if K > 5
uniform SAMPLER u_s5;
#endif
#if K > 6
uniform SAMPLER u_s6;
#endif
#if K > 7
uniform SAMPLER u_s7;
#endif
uniform int u_count;     // samples
uniform int u_layers;    // layers that count (the peel's stop rules), at most K
uniform ivec2 u_size;
uniform bool u_ortho;
uniform float u_tolerance;  // the depth tolerance, eye depth
uniform float u_footprint;  // a pixel's size at unit distance (perspective) or in model units
#if BAND
// per face, how far in front of a smooth contour's sample it must lie to hide it: its size
// times levels.py's reach where a smooth surface folds over its own contour, 0 elsewhere
uniform sampler2D u_reach;
#endif

#ifndef REMAP
#define REMAP 0
#endif
#if REMAP
// the faces k-buffer drew some faces alone (contour_cull.comp): its face i is face u_remap[i]
uniform isampler2D u_remap;
#define REMAPPED(t) ((t) < 0 ? (t) : TABLE_ROW(u_remap, (t)).r)
#else
#define REMAPPED(t) (t)
#endif

const int BIG = 0x7fffffff;

// more than ``limit`` (eye depth) in front
bool in_front(vec4 plane, vec3 eye, float limit) {
    precise float d = plane.x * eye.x + plane.y * eye.y + plane.z * eye.z;
    float c = plane.w;
    if (u_ortho) {
        // the plane meets the ray eye + u (0, 0, 1) at u = (c - n . eye) / n_z
        precise float ahead = (c - d) * sign(plane.z);
        precise float bound = limit * abs(plane.z);
        return ahead > bound;
    }
    // the ray t * eye meets the plane at t = c / (n . eye), (1 - t) times the eye depth -eye.z
    // in front: 0 < t < 1 - limit / -eye.z
    precise float far = abs(d) * (1.0 - limit / -eye.z);
    return c * d > 0.0 && abs(c) < far;
}

// surface ``tri`` more than ``limit`` in front of a sample, or, of a smooth contour's sample
// (``contour``), more than its reach where the surface folds over the contour
bool hides(int tri, vec3 eye, float limit, bool contour) {
#if BAND
    if (contour) {
        limit = max(limit, TABLE_ROW(u_reach, tri).r);
    }
#endif
    return in_front(TABLE_ROW(u_planes, tri), eye, limit);
}

// pixel (x right, y down) clamped to the image, in OpenGL rows
ivec2 texel(ivec2 p) {
    p = clamp(p, ivec2(0), u_size - 1);
    return ivec2(p.x, u_size.y - 1 - p.y);
}

#if STACKS
// (surfaces counted in front by more than ``limit``, surfaces there) from the read-back stack
// at q; counting stops at ``bound`` surfaces in front; seen[0]: the stack's first row
ivec2 stack_at(ivec2 q, vec3 eye, float limit, int own0, int own1, int bound, bool contour, out int seen[K]) {
    ivec2 where = texelFetch(u_where, q, 0).xy;
    seen[0] = where.x;
    int front = 0;
    for (int k = 0; k < where.y; ++k) {
        int tri = TABLE_ROW(u_faces, where.x + k).r;
        if (tri != own0 && tri != own1 && hides(tri, eye, limit, contour)) ++front;
        if (front >= bound) return ivec2(front, k + 1);
    }
    return ivec2(front, where.y);
}

// the face of surface ``index`` of the stack that stack_at read
int seen_face(int seen[K], int index) {
    return TABLE_ROW(u_faces, seen[0] + index).r;
}
#else
// one surface of the stack: stop at the first empty one, count it in front or not; stop
// too once ``bound`` surfaces are in front (the caller wants no more); its face kept in
// seen[I] for the sides' check (reading it again there would be K more texel fetches:
// llvmpipe runs every case of a switch on a lane's value)
#define SURFACE(S, I)                                                               \
    if (count < u_layers) {                                                         \
        int tri = REMAPPED(FACE1(S, q) - 1);                                        \
        seen[I] = tri;                                                              \
        if (tri < 0) return ivec2(front, count);                                    \
        ++count;                                                                    \
        if (tri != own0 && tri != own1 && hides(tri, eye, limit, contour)) ++front;       \
        if (front >= bound) return ivec2(front, count);                             \
    }

// (surfaces counted in front by more than ``limit``, surfaces there), unrolled over the K
// targets; counting stops at ``bound`` surfaces in front; seen: the faces of the surfaces counted
ivec2 stack_at(ivec2 q, vec3 eye, float limit, int own0, int own1, int bound, bool contour, out int seen[K]) {
    int front = 0;
    int count = 0;
    SURFACE(u_s0, 0)
#if K > 1
    SURFACE(u_s1, 1)
#endif
#if K > 2
    SURFACE(u_s2, 2)
#endif
#if K > 3
    SURFACE(u_s3, 3)
#endif
#if K > 4
    SURFACE(u_s4, 4)
#endif
#if K > 5
    SURFACE(u_s5, 5)
#endif
#if K > 6
    SURFACE(u_s6, 6)
#endif
#if K > 7
    SURFACE(u_s7, 7)
#endif
    return ivec2(front, count);
}

int seen_face(int seen[K], int index) {
    return seen[index];
}
#endif

void main() {
    int i = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (i >= u_count) return;
    Sample s = samples[i];
    vec3 eye = s.eye;
    int own0 = s.own.z;
    int own1 = s.own.w;
    bool solid = (s.flags & 1) != 0;
    bool contour = (s.flags & 4) != 0;
    ivec2 px = s.pixel.xy;
    int best = BIG;
    // a pixel can only lower the minimum: its count stops at the best so far, and none
    // goes below zero
    int seen[K];
    for (int n = 0; n < 4 && best > 0; ++n) {
        ivec2 st = stack_at(texel(px + ivec2(n % 2, n / 2)), eye, u_tolerance, own0, own1, best, contour, seen);
        int front = (solid && st.y == 0) ? BIG : st.x;
        best = min(best, front);
    }
    if (best == BIG) best = 0;
    ivec2 sides = ivec2(-1);
    if ((s.flags & 2) != 0) {
        // the surface at the line's depth beside it: within a pixel's footprint (levels.py's side_limit)
        float side_limit = u_ortho ? u_footprint : u_footprint * -eye.z;
        for (int side = 0; side < 2; ++side) {
            ivec2 q = texel(side == 0 ? s.pixel.zw : s.own.xy);
            ivec2 st = stack_at(q, eye, side_limit, own0, own1, BIG, false, seen);
            sides[side] = st.x < st.y ? seen_face(seen, st.x) : -1;
        }
    }
    result[i] = ivec4(best, sides, 0);
}

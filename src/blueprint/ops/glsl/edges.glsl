// Edge intensity of one depth layer at a pixel: discontinuities of coverage (borders), part ID
// (part boundaries), normal (creases) and depth (silhouettes). Each discontinuity between two
// neighbouring pixels marks both of them, so lines are centred on the true boundary.
#include "depth.glsl"
#ifndef ID_SILHOUETTES
#define ID_SILHOUETTES 0
#endif
#if ID_SILHOUETTES
#include "idsil_vertex.glsl"
#endif
#ifndef SMOOTH_CONTOURS
#define SMOOTH_CONTOURS 0
#endif
#if SMOOTH_CONTOURS
#ifndef EVERY_FACE_CONTOURED
#define EVERY_FACE_CONTOURED 0
#endif
// the contour lines' levels count every layer this pass draws (below u_contour_layers)
#ifndef CONTOURS_EVERY_LAYER
#define CONTOURS_EVERY_LAYER 0
#endif
// the mesh is one part: no part boundary
#ifndef ONE_PART
#define ONE_PART 0
#endif
#if !EVERY_FACE_CONTOURED
#include "table.glsl"
// 1 for each face whose outline is drawn as a line of the smooth surface's contour instead
// (vector/contour_ink.py), by face + 1 as the IDs hold it; with EVERY_FACE_CONTOURED (a
// scan: every face smooth) no table is read, which saves a software rasteriser five reads a
// pixel and layer
uniform isampler2D u_contoured;
#endif
// the layers whose contours the lines draw: deeper ones keep the mesh's outline
uniform int u_contour_layers;

// Whether a covered sample's face leaves its outline to the contour lines
bool contoured(int face1) {
#if EVERY_FACE_CONTOURED
    return true;
#else
    return TABLE_ROW(u_contoured, face1).r != 0;
#endif
}
#endif

// The layer's samples at pixel q, the pixel itself (i = -1) or its neighbour OFFSETS[i]: from
// the G-buffer's textures unless the including shader has them already (EDGE_SAMPLES).
#ifndef EDGE_SAMPLES
uniform sampler2D u_depth;       // the layer's depth attachment, 1.0 where nothing was drawn
uniform sampler2D u_normal;
uniform isampler2D u_ids;
#define EDGE_LAST (textureSize(u_depth, 0) - 1)
#define EDGE_DEPTH(q, i) texelFetch(u_depth, q, 0).r
#define EDGE_NORMAL(q, i) texelFetch(u_normal, q, 0).xyz
#define EDGE_IDS(q, i) texelFetch(u_ids, q, 0).xy
#define EDGE_RING_COVERED(q, r) (texelFetch(u_depth, q, 0).r < 1.0)
#endif
uniform vec2 u_normal_cos;       // (cos of the angle where creases start, cos where they are full)
uniform float u_depth_threshold; // jumps beyond this many pixel footprints are silhouettes
uniform float u_pixel_angle;     // pixel footprint per unit depth (perspective) or per pixel (ortho)
uniform bool u_part_edges;
// Ink of depth layers >= 1 over layer 0's: hidden lines narrower than the edges' own width keep
// that share of their ink (_widths.glsl), taken here where no pass widens the lines after.
uniform float u_hidden_ink;
// Triangle-ID silhouettes as one more edge source: compiled in only where asked for (the
// ID_SILHOUETTES define), since a software rasteriser pays for the dead branch on every pixel.

const ivec2 OFFSETS[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));
// The pixels two steps from p (RING), and which three of them neighbour OFFSETS[i] besides p.
const ivec2 RING[8] = ivec2[8](
    ivec2(-2, 0), ivec2(2, 0), ivec2(0, -2), ivec2(0, 2),
    ivec2(-1, -1), ivec2(1, -1), ivec2(-1, 1), ivec2(1, 1));
const int RING_OF[12] = int[12](0, 4, 6, 1, 5, 7, 2, 4, 5, 3, 6, 7);

// Eye-space position of pixel q at window depth z (the projection is centred on the image).
vec3 eye_position(ivec2 q, float z) {
    float d = eye_depth(z);
    vec2 xy = (vec2(q) + 0.5 - 0.5 * vec2(EDGE_LAST + 1)) * u_pixel_angle;
    return u_depth_range.z > 0.5 ? vec3(xy, -d) : vec3(xy * d, -d);
}

float crease(vec3 a, vec3 b) {
    return 1.0 - smoothstep(u_normal_cos.y, u_normal_cos.x, dot(a, b));
}

#if SMOOTH_CONTOURS && EVERY_FACE_CONTOURED && CONTOURS_EVERY_LAYER
// Every face's outline in every layer drawn is the contour lines' (a scan's frame within the
// layers their levels count): what edge_value below leaves to draw is part boundaries alone,
// and a software rasteriser runs none of its other reads and tests.
float edge_value(ivec2 p, int layer) {
#if ONE_PART
    return 0.0;
#endif
    if (!u_part_edges || EDGE_DEPTH(p, -1) >= 1.0) {
        return 0.0;
    }
    ivec2 last = EDGE_LAST;
    int part = EDGE_IDS(p, -1).y;
    bool part_edge = false;
    for (int i = 0; i < 4; ++i) {
        ivec2 q = clamp(p + OFFSETS[i], ivec2(0), last);
        part_edge = part_edge || (EDGE_DEPTH(q, i) < 1.0 && EDGE_IDS(q, i).y != part);
    }
    return part_edge ? 1.0 : 0.0;
}
#else
float edge_value(ivec2 p, int layer) {
    ivec2 last = EDGE_LAST;
    float zc = EDGE_DEPTH(p, -1);
    float z[4];
    bool covered[4];
    bool any_covered = false;
    for (int i = 0; i < 4; ++i) {
        // outside the image counts as more of the same, so the frame draws no line
        ivec2 q = clamp(p + OFFSETS[i], ivec2(0), last);
        z[i] = EDGE_DEPTH(q, i);
        covered[i] = z[i] < 1.0;
        any_covered = any_covered || covered[i];
    }
    // A surface that covers a pixel of a layer and none of its neighbours lies under the
    // pixel: the noise folds of a scan beside a contour, two more surfaces at one pixel, or
    // something smaller than a pixel. Its border would be a speck.
    if (!any_covered) {
        return 0.0;
    }
    if (zc >= 1.0) {
#if SMOOTH_CONTOURS
        // beside surfaces whose outline the contour lines draw, the border is theirs
        bool left = layer < u_contour_layers;
        for (int i = 0; i < 4; ++i) {
            left = left && (!covered[i] || contoured(EDGE_IDS(clamp(p + OFFSETS[i], ivec2(0), last), i).x));
        }
        if (left) {
            return 0.0;
        }
#endif
        // the ring read at once: a software rasteriser runs every lane through each read
        bool ring[8];
        for (int r = 0; r < 8; ++r) {
            ring[r] = EDGE_RING_COVERED(clamp(p + RING[r], ivec2(0), last), r);
        }
        for (int i = 0; i < 4; ++i) {
            if (covered[i] && (ring[RING_OF[3 * i]] || ring[RING_OF[3 * i + 1]] || ring[RING_OF[3 * i + 2]])) {
                return 1.0;
            }
        }
        return 0.0;
    }
    // Each kind of sample read for every neighbour before anything is decided: llvmpipe pays
    // several times over for reads between early returns in a loop.
    ivec2 own = EDGE_IDS(p, -1);
    ivec2 ids[4];
    for (int i = 0; i < 4; ++i) {
        ids[i] = EDGE_IDS(clamp(p + OFFSETS[i], ivec2(0), last), i);
    }
#if SMOOTH_CONTOURS
    // Inside a smooth surface whose outline the contour lines draw, its borders, jumps and the
    // normals' turns at its folds are that outline seen through the mesh's noise: only part
    // boundaries are left to draw.
    bool within = layer < u_contour_layers && contoured(own.x);
    for (int i = 0; i < 4; ++i) {
        within = within && (!covered[i] || contoured(ids[i].x));
    }
    if (within) {
        bool part_edge = false;
        for (int i = 0; i < 4; ++i) {
            part_edge = part_edge || (u_part_edges && covered[i] && ids[i].y != own.y);
        }
        return part_edge ? 1.0 : 0.0;
    }
#endif
    bool border = false;
    for (int i = 0; i < 4; ++i) {
        border = border || !covered[i] || (u_part_edges && ids[i].y != own.y);
    }
    if (border) {
        return 1.0;
    }
    vec3 nc = EDGE_NORMAL(p, -1);
    vec3 n[4];
    for (int i = 0; i < 4; ++i) {
        n[i] = EDGE_NORMAL(clamp(p + OFFSETS[i], ivec2(0), last), i);
    }
#if ID_SILHOUETTES
    {
        bool loaded = false;
        for (int i = 0; i < 4; ++i) {
            int other = ids[i].x;
            if (other != own.x) {
                if (!loaded) {
                    load_own(own.x - 1);
                    loaded = true;
                }
                if (!adjacent_to_own(other - 1)) {
                    return 1.0;
                }
            }
        }
    }
#endif
    float e = 0.0;
    for (int i = 0; i < 4; ++i) {
        e = max(e, crease(nc, n[i]));
    }
    // Window depth is affine in screen space on any plane, perspective or not, so its second
    // difference is zero on planes and large across a jump; measured in eye-depth units and
    // pixel footprints it means the same at every distance and zoom.
    float dc = eye_depth(zc);
    float footprint = u_depth_range.z > 0.5 ? u_pixel_angle : u_pixel_angle * dc;
    float scale = eye_depth_slope(dc) / (footprint * u_depth_threshold);
    float jump = max(abs(z[0] + z[1] - 2.0 * zc), abs(z[2] + z[3] - 2.0 * zc)) * scale;
    float outline = smoothstep(1.0, 2.0, jump);
    // A jump is an outline only where one side lies off the other's tangent plane or turns
    // from it by as much as a crease starts at: the near side of a real one grazes the view,
    // but the far surface neither passes through it nor runs parallel. Where both sides are
    // one smooth sheet seen edge-on -- a curved surface just short of its contour, or the
    // noise folds of a scan there -- drawing the jump smears the contour into broken pieces.
    if (outline > 0.0) {
        vec3 pc = eye_position(p, zc);
        float apart = 0.0;
        bool turned = false;
        for (int i = 0; i < 4; ++i) {
            vec3 d = eye_position(clamp(p + OFFSETS[i], ivec2(0), last), z[i]) - pc;
            apart = max(apart, max(abs(dot(nc, d)), abs(dot(n[i], d))));
            turned = turned || dot(nc, n[i]) < u_normal_cos.x;
        }
        if (!turned) {
            outline *= smoothstep(0.75, 1.0, apart / (footprint * u_depth_threshold));
        }
    }
    return max(e, outline);
}

#endif

// edge_value in the ink of depth layer ``layer``
float layer_edge_value(ivec2 p, int layer) {
    return edge_value(p, layer) * (layer > 0 ? u_hidden_ink : 1.0);
}

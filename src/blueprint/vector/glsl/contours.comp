// The smooth contours of a mesh drawn flat (one placement, the identity) for one view, from
// the vertex and index buffers it is drawn with (vector/contour_gpu.py): an invocation a face.
// The rules are those of silhouette/contours.py and vector/lines.py, on the prepared vertex
// normals: a face is smooth where no vertex lies on a crease, a border or a non-manifold edge
// (u_smooth, from the preparation), it is not degenerate and every vertex normal lies on its
// side; a smooth face seen edge-on (|cos| <= u_edge_on) keeps its mesh outline; the contour is
// the zero set of the interpolated n . v, a vertex with n . v at most u_vertex_edge_on of
// |v| counting as turned away, so a face holds at most one segment, and its ends are found
// from each edge's lower vertex, so both faces of an edge find one point.
// Also written, a row a face (rows from u_faces on zero, none there): the face's eye-space
// plane (n, c) and, for a smooth face not seen edge-on with a vertex normal within the grazing
// band, its longest edge times the band's reach (0 elsewhere): occlusion.comp's u_planes and
// u_reach tables.
#include "table.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 5) readonly buffer Vertices { float vertices[]; };
layout(std430, binding = 6) readonly buffer Indices { uint indices[]; };
// bit f % 32 of word f / 32: face f is smooth (no vertex on a feature)
layout(std430, binding = 7) readonly buffer Smooth { uint smooth_bits[]; };
// bit f % 32 of word f / 32: face f's outline is the contours' (smooth, not seen edge-on)
layout(std430, binding = 8) writeonly buffer Contoured { uint contoured_bits[]; };
layout(std430, binding = 9) buffer Count { uint segment_count; };
// a segment's two ends in model coordinates, the face's number in the first's w (int bits),
// then the vertices of the edges they lie on (the lower first): the ends the segments of the
// face across each edge share
layout(std430, binding = 10) writeonly buffer Segments { vec4 segments[]; };
// each face's box on screen in tiles of u_tile pixels, x0 | y0 << 8 | x1 << 16 | y1 << 24 (y down,
// a pixel's margin; first past last where it lies off the screen; every tile where a corner lies
// behind the eye): which faces can cover the pixels the occlusion pass reads (contour_cull.comp)
layout(std430, binding = 11) writeonly buffer Bounds { uint bounds[]; };
layout(rgba32f, binding = 0) writeonly uniform image2D u_planes;
layout(r32f, binding = 1) writeonly uniform image2D u_reach;

uniform int u_faces;
uniform int u_rows;           // the tables' rows: u_faces or more, a whole texture row
uniform uint u_capacity;      // segments the buffer holds
uniform mat4 u_view;          // model to eye
uniform vec3 u_toward;        // the eye (perspective) or the direction to it (orthographic), model space
uniform bool u_ortho;
uniform float u_edge_on;      // a face seen within this |cos| of edge-on
uniform float u_vertex_edge_on;
uniform float u_grazing;      // sine of the grazing band's angle
uniform float u_band_reach;   // sizes of its own a face of the band reaches (GRAZING_REACH)
uniform mat4 u_projection;    // eye to clip
uniform vec2 u_size;          // the picture's pixels
uniform float u_tile;         // pixels a tile of the bounds

shared uint s_contoured[2];

// the face's tiles on screen (Bounds)
uint tile_bounds(vec3 p[3]) {
    vec2 lo = vec2(1e30);
    vec2 hi = vec2(-1e30);
    for (int k = 0; k < 3; ++k) {
        vec4 clip = u_projection * (u_view * vec4(p[k], 1.0));
        if (clip.w <= 0.0) {
            return 0xffffffffu;
        }
        vec2 pixel = vec2(0.5 + 0.5 * clip.x / clip.w, 0.5 - 0.5 * clip.y / clip.w) * u_size;
        lo = min(lo, pixel);
        hi = max(hi, pixel);
    }
    lo -= 1.0;
    hi += 1.0;
    if (any(greaterThan(lo, u_size)) || any(lessThan(hi, vec2(0.0)))) {
        return 1u;  // x0 = 1 past x1 = 0: no tile
    }
    uvec2 first = uvec2(clamp(floor(max(lo, vec2(0.0)) / u_tile), 0.0, 255.0));
    uvec2 last = uvec2(clamp(floor(min(hi, u_size) / u_tile), 0.0, 255.0));
    return first.x | first.y << 8 | last.x << 16 | last.y << 24;
}

vec3 position(uint v) { return vec3(vertices[7u * v], vertices[7u * v + 1u], vertices[7u * v + 2u]); }
vec3 normal(uint v) { return vec3(vertices[7u * v + 3u], vertices[7u * v + 4u], vertices[7u * v + 5u]); }

void main() {
    uint local = gl_LocalInvocationID.x;
    if (local < 2u) {
        s_contoured[local] = 0u;
    }
    barrier();
    int f = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    bool contoured = false;
    vec4 plane = vec4(0.0);
    float reach = 0.0;
    if (f < u_faces) {
        uint v[3] = uint[3](indices[3 * f], indices[3 * f + 1], indices[3 * f + 2]);
        vec3 p[3] = vec3[3](position(v[0]), position(v[1]), position(v[2]));
        vec3 n[3] = vec3[3](normal(v[0]), normal(v[1]), normal(v[2]));
        bounds[f] = tile_bounds(p);
        vec3 cross_ = cross(p[1] - p[0], p[2] - p[0]);
        float area2 = length(cross_);
        if (area2 > 0.0) {
            vec3 unit = cross_ / area2;
            vec3 eye_normal = mat3(u_view) * unit;
            plane = vec4(eye_normal, dot(eye_normal, (u_view * vec4(p[0], 1.0)).xyz));
        }
        bool smooth_face = (smooth_bits[f >> 5] & (1u << (f & 31))) != 0u && area2 > 0.0;
        smooth_face = smooth_face && dot(cross_, n[0]) > 0.0 && dot(cross_, n[1]) > 0.0 && dot(cross_, n[2]) > 0.0;
        vec3 t0 = u_ortho ? u_toward : u_toward - p[0];
        bool edge_on = abs(dot(cross_, t0)) <= u_edge_on * area2 * length(t0);
        contoured = smooth_face && !edge_on;
        if (contoured) {
            float s[3];
            bool front[3];
            bool grazing = false;
            for (int k = 0; k < 3; ++k) {
                vec3 t = u_ortho ? u_toward : u_toward - p[k];
                float along = length(t);
                s[k] = dot(n[k], t);
                front[k] = s[k] > u_vertex_edge_on * along;
                grazing = grazing || abs(s[k]) < u_grazing * along * length(n[k]);
            }
            if (grazing) {
                float longest = max(max(distance(p[0], p[1]), distance(p[1], p[2])), distance(p[2], p[0]));
                reach = longest * u_band_reach;
            }
            if (front[0] != front[1] || front[1] != front[2]) {
                vec3 ends[2];
                uvec4 edges = uvec4(0u);
                int found = 0;
                for (int k = 0; k < 3; ++k) {
                    int j = (k + 1) % 3;
                    if (front[k] != front[j]) {
                        int lo = v[k] < v[j] ? k : j;
                        int hi = lo == k ? j : k;
                        float t = s[lo] / (s[lo] - s[hi]);
                        ends[found] = p[lo] + t * (p[hi] - p[lo]);
                        if (found == 0) {
                            edges.xy = uvec2(v[lo], v[hi]);
                        } else {
                            edges.zw = uvec2(v[lo], v[hi]);
                        }
                        found += 1;
                    }
                }
                uint at = atomicAdd(segment_count, 1u);
                if (at < u_capacity) {
                    segments[3u * at] = vec4(ends[0], intBitsToFloat(f));
                    segments[3u * at + 1u] = vec4(ends[1], 0.0);
                    segments[3u * at + 2u] = uintBitsToFloat(edges);
                }
            }
        }
        atomicOr(s_contoured[local >> 5], contoured ? 1u << (local & 31u) : 0u);
    }
    if (f < u_rows) {
        imageStore(u_planes, TABLE_AT(f), plane);
        imageStore(u_reach, TABLE_AT(f), vec4(reach));
    }
    barrier();
    // the workgroup's 64 faces start a word: its two words are its own
    if (local < 2u) {
        uint word = (gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x) * 2u + local;
        if (int(word * 32u) < u_faces) {
            contoured_bits[word] = s_contoured[local];
        }
    }
}

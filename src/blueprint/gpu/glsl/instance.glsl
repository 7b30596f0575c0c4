// A vertex placed by its instance (render.mesh.GpuMesh): an instance holds rows of its affine
// transform, rows of its normals' transform, its part and its first face, so a mesh used N
// times is uploaded once. A flattened model is one instance of the identity, whose products
// give its vertices to the bit. Every geometry program's vertex stage reads the vertex and
// its instance as attributes; with PLACEMENTS (a storage binding) a program that reads faces
// by their ID (the compute rasteriser, the A-buffer's resolve) finds a face's instance in the
// faces table instead (GpuMesh.bind_faces), placed by the same products; with ONE_PLACEMENT
// (a flattened model) it looks up nothing, and with UNPLACED (a draw of one instance of the
// identity) the vertex stage reads no instance.

// point p placed by the transform's rows x, y, z
vec3 place_point(vec4 x, vec4 y, vec4 z, vec3 p) {
    vec4 h = vec4(p, 1.0);
    return vec3(dot(x, h), dot(y, h), dot(z, h));
}

// normal n (zero where the mesh has none) turned by the normals' transform's rows
vec3 place_normal(vec3 nx, vec3 ny, vec3 nz, vec3 n) {
    return vec3(dot(nx, n), dot(ny, n), dot(nz, n));
}

#ifdef PLACEMENTS
#if ONE_PLACEMENT
// a flattened model: its one placement is the identity from face 0, so nothing is looked up
// (the products of the identity give its points to the bit)
int placement_of(int t) {
    return 0;
}

uint placed_face(int i, int t) {
    return uint(t);
}

vec3 placed_point(int i, vec3 p) {
    return p;
}

vec3 placed_normal(int i, vec3 n) {
    return n;
}

int placement_part(int i) {
    return 0;
}
#else
// render.mesh.PLACEMENT: ordered by first face ID, which rises strictly; base is where the
// instance's faces start in the index buffer (in faces)
struct Placement {
    vec4 x;
    vec4 y;
    vec4 z;
    vec4 nx;
    vec4 ny;
    vec4 nz;
    int part;
    int face;
    int base;
    int pad;
};
layout(std430, binding = PLACEMENTS) readonly buffer Placements {
    Placement placements[];
};

// the placement of face ID t: the last whose first face is at most t (a binary search)
int placement_of(int t) {
    int lo = 0, hi = placements.length() - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) >> 1;
        if (placements[mid].face <= t) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    return lo;
}

// face ID t's face in the index buffer, of its placement i
uint placed_face(int i, int t) {
    return uint(placements[i].base + (t - placements[i].face));
}

vec3 placed_point(int i, vec3 p) {
    return place_point(placements[i].x, placements[i].y, placements[i].z, p);
}

vec3 placed_normal(int i, vec3 n) {
    return place_normal(placements[i].nx.xyz, placements[i].ny.xyz, placements[i].nz.xyz, n);
}

int placement_part(int i) {
    return placements[i].part;
}
#endif
#else
in vec3 in_position;
in vec3 in_normal;
in int in_part;
#ifndef UNPLACED
#define UNPLACED 0
#endif
#if UNPLACED
// each draw one instance of the identity in part 0 (a flattened model): its vertices are drawn
// as they lie, its first face a uniform the draw sets (GpuMesh.vao), and no instance
// attribute is read (llvmpipe shades vertices on the drawing thread, a fetch each)
uniform int u_first_face;

int first_face() {
    return u_first_face;
}

vec3 placed_position() {
    return in_position;
}

vec3 placed_normal() {
    return in_normal;
}

int placed_part() {
    return in_part;
}
#else
in vec4 i_x;
in vec4 i_y;
in vec4 i_z;
in vec3 i_nx;
in vec3 i_ny;
in vec3 i_nz;
in int i_part;
in int i_face;

// the first face ID of the vertex's instance
int first_face() {
    return i_face;
}

// the vertex in the scene's coordinates
vec3 placed_position() {
    return place_point(i_x, i_y, i_z, in_position);
}

// its normal in the scene's coordinates (zero where the mesh has none)
vec3 placed_normal() {
    return place_normal(i_nx, i_ny, i_nz, in_normal);
}

// its part: the vertex's own within a flattened block, plus the instance's
int placed_part() {
    return in_part + i_part;
}
#endif
#endif

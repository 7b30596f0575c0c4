// Adjacency by vertex storage (paper 002, section 4.2): the three corner positions of every
// triangle, 3 consecutive entries per face; two triangles are adjacent when a corner of one lies
// within the tolerance of a corner of the other. Positions, not indices, so triangle soups and
// meshes whose vertices are repeated per face work unwelded. Nothing here depends on topology:
// a deforming mesh that splits or merges needs only its new positions.
uniform float u_tolerance2;  // squared distance under which two corners are the same vertex

#ifdef IDSIL_CORNERS_SSBO
// the same buffer the ID pass draws from (compute path)
layout(std430, binding = 0) readonly buffer IdsilCorners {
    float idsil_corner_data[];
};
vec3 corner(int i) {
    return vec3(idsil_corner_data[3 * i], idsil_corner_data[3 * i + 1], idsil_corner_data[3 * i + 2]);
}
#else
uniform sampler2D u_corners;  // RGB32F, corner i at (i % 4096, i / 4096)
vec3 corner(int i) {
    return texelFetch(u_corners, ivec2(i & 4095, i >> 12), 0).xyz;
}
#endif

vec3 idsil_own[3];

void load_own(int face) {
    for (int k = 0; k < 3; ++k) {
        idsil_own[k] = corner(3 * face + k);
    }
}

bool adjacent_to_own(int other) {
    for (int k = 0; k < 3; ++k) {
        vec3 c = corner(3 * other + k);
        for (int j = 0; j < 3; ++j) {
            vec3 d = c - idsil_own[j];
            if (dot(d, d) <= u_tolerance2) {
                return true;
            }
        }
    }
    return false;
}

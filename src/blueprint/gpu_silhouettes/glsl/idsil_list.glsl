// Adjacency by ID lists (paper 002, sections 4.1 and 4.3): precomputed for a fixed topology,
// per vertex the sorted list of the triangles around it, all lists appended in one texture and
// found through a pointer table of (start, count). A neighbour triangle is adjacent when it is
// in the list of one of the own triangle's three vertices; a binary search keeps vertices shared
// by many triangles (fans, the axis of a cylinder cut into wedges) cheap.
uniform isampler2D u_face_vertices;  // RGB32I: vertex ids of face i at (i % 4096, i / 4096)
uniform isampler2D u_pointers;       // RG32I: (start, count) of vertex v's list
uniform isampler2D u_lists;          // R32I: the lists, appended, each ascending

ivec2 idsil_at(int i) {
    return ivec2(i & 4095, i >> 12);
}

ivec2 idsil_own[3];

void load_own(int face) {
    ivec3 v = texelFetch(u_face_vertices, idsil_at(face), 0).xyz;
    for (int k = 0; k < 3; ++k) {
        idsil_own[k] = texelFetch(u_pointers, idsil_at(v[k]), 0).xy;
    }
}

bool in_list(ivec2 list, int face) {
    int lo = list.x;
    int hi = list.x + list.y - 1;
    while (lo <= hi) {
        int mid = (lo + hi) >> 1;
        int value = texelFetch(u_lists, idsil_at(mid), 0).r;
        if (value == face) {
            return true;
        }
        if (value < face) {
            lo = mid + 1;
        } else {
            hi = mid - 1;
        }
    }
    return false;
}

bool adjacent_to_own(int other) {
    return in_list(idsil_own[0], other) || in_list(idsil_own[1], other) || in_list(idsil_own[2], other);
}

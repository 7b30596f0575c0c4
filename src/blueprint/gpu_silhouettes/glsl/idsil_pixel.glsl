// Triangle-ID silhouettes of one depth layer at one pixel (paper 002, section 4): the pixel's
// triangle is compared with the triangles of its four neighbours; a neighbour triangle that is
// not adjacent to it (shares no vertex) marks a silhouette, and so does coverage changing
// between the two pixels (an outline against the background or against the layer's holes).
// No depth comparison, no normals, no threshold. The test is symmetric, so both pixels of a
// pair mark and lines lie centred on the boundary, two pixels wide, like the renderer's edges.
//
// The including file defines the adjacency test first:
//   void load_own(int face);            fetch what the test needs of the pixel's own triangle
//   bool adjacent_to_own(int other);    whether `other` shares a vertex with it

uniform sampler2D u_depth;   // the layer's depth attachment, 1.0 where nothing was drawn
uniform isampler2D u_ids;    // face + 1 in .x; stale where the depth says empty

float idsil_value(ivec2 p) {
    ivec2 last = textureSize(u_depth, 0) - 1;
    // outside the image counts as more of the same, so the frame draws no line
    ivec2 q0 = ivec2(max(p.x - 1, 0), p.y);
    ivec2 q1 = ivec2(min(p.x + 1, last.x), p.y);
    ivec2 q2 = ivec2(p.x, max(p.y - 1, 0));
    ivec2 q3 = ivec2(p.x, min(p.y + 1, last.y));
    bvec4 near = lessThan(
        vec4(texelFetch(u_depth, q0, 0).r, texelFetch(u_depth, q1, 0).r, texelFetch(u_depth, q2, 0).r,
             texelFetch(u_depth, q3, 0).r),
        vec4(1.0));
    bool covered = texelFetch(u_depth, p, 0).r < 1.0;
    if (any(notEqual(near, bvec4(covered)))) {
        return 1.0;  // coverage changes: an outline, drawn on both sides
    }
    if (!covered) {
        return 0.0;
    }
    int face = texelFetch(u_ids, p, 0).x - 1;
    ivec4 others = ivec4(texelFetch(u_ids, q0, 0).x, texelFetch(u_ids, q1, 0).x, texelFetch(u_ids, q2, 0).x,
                         texelFetch(u_ids, q3, 0).x) - 1;
    bvec4 changed = notEqual(others, ivec4(face));
    if (!any(changed)) {
        return 0.0;  // inside one triangle, as most pixels are
    }
    // the own triangle is fetched once, and only where the triangle changes
    load_own(face);
    for (int i = 0; i < 4; ++i) {
        if (changed[i] && !adjacent_to_own(others[i])) {
            return 1.0;
        }
    }
    return 0.0;
}

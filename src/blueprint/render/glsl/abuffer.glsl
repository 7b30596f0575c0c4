// The A-buffer: every fragment of one geometry pass in a list per pixel. u_head holds the first
// node + 1 of each pixel's list (0: none); node i is surface i of the pass, packed as a
// k-buffer surface (kbuffer.glsl), and link i the next node + 1 of its pixel's list. The
// resolve (abuffer_resolve.comp) puts each pixel's layers in peel order, chained through
// order i from the pixel's u_cursor. Read and written through AB_NODE, AB_LINK, AB_ORDER and
// their AB_SET_ forms: in storage buffers, or with AB_IMAGES in images, entry i at
// (i % AB_ROW, i / AB_ROW): llvmpipe loads a storage buffer a lane at a time, far slower
// than an image load.
// With SLIM the geometry pass writes each fragment's depth and face alone into slim[] (see
// abuffer.frag), and the resolve fills node i (normal, part) only for the fragments it keeps
// as layers: fragment(i) reads either form's depth and face.
#ifndef SLIM
#define SLIM 0
#endif
#ifndef AB_SPLIT
#define AB_SPLIT 0
#endif
#define AB_ROW 4096
#if AB_IMAGES
layout(binding = 5, rgba32ui) coherent uniform uimage2D u_nodes;
layout(binding = 6, r32ui) coherent uniform uimage2D u_links;
layout(binding = 7, r32ui) coherent uniform uimage2D u_order;

ivec2 ab_at(uint i) {
    return ivec2(int(i % uint(AB_ROW)), int(i / uint(AB_ROW)));
}

#define AB_NODE(i) imageLoad(u_nodes, ab_at(i))
#define AB_LINK(i) imageLoad(u_links, ab_at(i)).x
#define AB_ORDER(i) imageLoad(u_order, ab_at(i)).x
#define AB_SET_NODE(i, v) imageStore(u_nodes, ab_at(i), (v))
#define AB_SET_LINK(i, v) imageStore(u_links, ab_at(i), uvec4(v))
#define AB_SET_ORDER(i, v) imageStore(u_order, ab_at(i), uvec4(v))
#else
layout(std430, binding = 0) coherent buffer Nodes {
    uvec4 nodes[];
};
layout(std430, binding = 1) coherent buffer Links {
    uint links[];
};
layout(std430, binding = 2) coherent buffer Order {
    uint order[];
};
#if AB_SPLIT
// nodes from AB_SPLIT on, in a second binding of the nodes' buffer: one binding holds some 2 GiB
// at most (GL_MAX_SHADER_STORAGE_BLOCK_SIZE), 134 M nodes
layout(std430, binding = 16) coherent buffer NodesHigh {
    uvec4 nodes_high[];
};

uvec4 ab_node(uint i) {
    return i < uint(AB_SPLIT) ? nodes[i] : nodes_high[i - uint(AB_SPLIT)];
}

void ab_set_node(uint i, uvec4 v) {
    if (i < uint(AB_SPLIT)) {
        nodes[i] = v;
    } else {
        nodes_high[i - uint(AB_SPLIT)] = v;
    }
}

#define AB_NODE(i) ab_node(i)
#define AB_SET_NODE(i, v) ab_set_node((i), (v))
#else
#define AB_NODE(i) nodes[i]
#define AB_SET_NODE(i, v) nodes[i] = (v)
#endif
#define AB_LINK(i) links[i]
#define AB_ORDER(i) order[i]
#define AB_SET_LINK(i, v) links[i] = (v)
#define AB_SET_ORDER(i, v) order[i] = (v)
#endif
// (fragments drawn, nodes held, pixels whose list was too long to sort in registers, triangle-
// tile pairs the compute rasteriser listed: abuffer_raster.comp); the most
// layers of any pixel comes from Depths, not from an atomic a pixel on one shared word, which
// a software rasteriser runs a lane at a time
layout(std430, binding = 3) coherent buffer Totals {
    uint drawn;
    uint capacity;
    uint long_lists;
    uint pairs;
};
// pixels by the number of layers they hold, the last entry for that many or more
#define MOST_LAYERS 256
layout(std430, binding = 4) coherent buffer Depths {
    uint pixels_with[MOST_LAYERS + 1];
};
#if SLIM
// (window depth bits, bit 31 set for a back face; face + 1) of each fragment
layout(std430, binding = 7) coherent buffer Slim {
    uvec2 slim[];
};

uvec4 fragment(uint i) {
    uvec2 s = slim[i];
    return uvec4(s.x, 0u, 0u, s.y);
}
#else
uvec4 fragment(uint i) {
    return AB_NODE(i);
}
#endif

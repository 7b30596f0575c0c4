// The A-buffer: every fragment of one geometry pass in a list per pixel. u_head holds the first
// node + 1 of each pixel's list (0: none); node i is surface i of the pass, packed as a
// k-buffer surface (kbuffer.glsl), and links[i] the next node + 1 of its pixel's list. The
// resolve (abuffer_resolve.comp) puts each pixel's layers in peel order in order[], from the
// pixel's u_cursor. With SLIM the geometry pass writes each fragment's depth and face alone
// into slim[] (see abuffer.frag), and the resolve fills node i (normal, part) only for the
// fragments it keeps as layers: fragment(i) reads either form's depth and face.
#ifndef SLIM
#define SLIM 0
#endif
layout(std430, binding = 0) coherent buffer Nodes {
    uvec4 nodes[];
};
layout(std430, binding = 1) coherent buffer Links {
    uint links[];
};
layout(std430, binding = 2) coherent buffer Order {
    uint order[];
};
// (fragments drawn, nodes held, the most layers of any pixel, pixels whose list was too long
// to sort in registers)
layout(std430, binding = 3) coherent buffer Totals {
    uint drawn;
    uint capacity;
    uint deepest;
    uint long_lists;
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
    return nodes[i];
}
#endif

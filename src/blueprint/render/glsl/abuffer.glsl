// The A-buffer: every fragment of one geometry pass in a list per pixel. u_head holds the first
// node + 1 of each pixel's list (0: none); node i is surface i of the pass, packed as a
// k-buffer surface (kbuffer.glsl), and links[i] the next node + 1 of its pixel's list. The
// resolve (abuffer_resolve.comp) puts each pixel's layers in peel order in order[], from the
// pixel's u_cursor.
layout(std430, binding = 0) coherent buffer Nodes {
    uvec4 nodes[];
};
layout(std430, binding = 1) coherent buffer Links {
    uint links[];
};
layout(std430, binding = 2) coherent buffer Order {
    uint order[];
};
// (fragments drawn, nodes held, pixels whose list was too long to sort in registers); the most
// layers of any pixel comes from Depths, not from an atomic a pixel on one shared word (on
// llvmpipe that took a fifth of the resolve)
layout(std430, binding = 3) coherent buffer Totals {
    uint drawn;
    uint capacity;
    uint long_lists;
};
// pixels by the number of layers they hold, the last entry for that many or more
#define MOST_LAYERS 256
layout(std430, binding = 4) coherent buffer Depths {
    uint pixels_with[MOST_LAYERS + 1];
};

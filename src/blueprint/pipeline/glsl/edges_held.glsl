// The edges operation's samples (edges.glsl) held in arrays: the pixel (0) and its neighbours
// OFFSETS[i] (i + 1), filled by the including shader from wherever it reads the layer (an
// A-buffer's lists, a k-buffer's surfaces) before it calls layer_edge_value. The including
// shader defines EDGE_LAST and EDGE_RING_COVERED, and includes edges.glsl after this.
float sample_depth[5];
vec3 sample_normal[5];
ivec2 sample_ids[5];
#define EDGE_SAMPLES 1
#define EDGE_DEPTH(q, i) sample_depth[(i) + 1]
#define EDGE_NORMAL(q, i) sample_normal[(i) + 1]
#define EDGE_IDS(q, i) sample_ids[(i) + 1]

// Row i of a table that gpu/tables.py lays out as a texture, TABLE_WIDTH rows a texture row.
// Compute passes read scattered rows this way, not from storage buffers: llvmpipe loads a
// storage buffer at indices that differ across a SIMD vector's lanes one lane at a time,
// and fetches texels for all lanes at once.
#define TABLE_WIDTH 4096
#define TABLE_AT(i) ivec2((i) & (TABLE_WIDTH - 1), (i) >> 12)
#define TABLE_ROW(table, i) texelFetch(table, TABLE_AT(i), 0)

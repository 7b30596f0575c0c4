// Samples lying on another line of lower rank, for vector/occlusion/coincident.py, which is
// the reference: one invocation per live sample walks the stretches in the 3 x 3 cells around
// it (its own first, then those beside it, then the corners), each cell's stretches sorted by
// the bin of their direction, then rank; in each of its bins, from the bin's first stretch up
// to its own rank, at most u_budget stretches in all; and tells whether one of another line
// passes within the distance and runs within the angle. The arithmetic is NumPy's, in single
// precision, operation by operation (precise: nothing fused), so the answers are the same.
#include "table.glsl"

layout(local_size_x = 64) in;

// live samples: pixel x, y and the direction of their line there x, y; cell, rank, line, and
// the first bin they look in plus 256 times the bins they look in
layout(std430, binding = 0) readonly buffer Live { vec4 live[]; };
layout(std430, binding = 1) readonly buffer LiveKeys { ivec4 live_keys[]; };
layout(std430, binding = 2) writeonly buffer Drop { int drop[]; };
// tables (gpu/tables.py) of the stretches in cell order: start pixel x, y and the step to the
// next sample x, y; the step's unit vector x, y and 1 / its length squared; bin times u_ranks
// plus rank, line; and of the cells: their first stretch, their stretches
uniform sampler2D u_steps;
uniform sampler2D u_units;
uniform isampler2D u_keys;
uniform isampler2D u_cells;

uniform int u_count;        // live samples
uniform int u_span;         // cells a row
uniform int u_ranks;        // ranks in all
uniform int u_bins;         // bins of direction
uniform int u_budget;       // stretches a sample looks at, at most
uniform float u_distance2;  // the distance squared, as NumPy compares it (single precision)
uniform float u_sin_limit;  // the largest single below the sine of the angle

const ivec2 NEIGHBOURS[9] = ivec2[9](
    ivec2(0, 0), ivec2(-1, 0), ivec2(0, -1), ivec2(0, 1), ivec2(1, 0),
    ivec2(-1, -1), ivec2(-1, 1), ivec2(1, -1), ivec2(1, 1));

// the first stretch in [lo, hi) whose key is at least the given one (hi where none is)
int first_at_least(int lo, int hi, int key) {
    while (lo < hi) {
        int mid = (lo + hi) >> 1;
        if (TABLE_ROW(u_keys, mid).x < key) lo = mid + 1; else hi = mid;
    }
    return lo;
}

void main() {
    int l = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (l >= u_count) return;
    vec4 me = live[l];
    ivec4 key = live_keys[l];
    int first_bin = key.w & 255;
    int bin_count = key.w >> 8;
    int left = u_budget;
    int found = 0;
    for (int n = 0; n < 9 && found == 0 && left > 0; ++n) {
        // the grid's margin keeps the probe inside
        int probe = key.x + NEIGHBOURS[n].x * u_span + NEIGHBOURS[n].y;
        ivec2 cell = TABLE_ROW(u_cells, probe).xy;
        int end = cell.x + cell.y;
        for (int b = 0; b < bin_count && found == 0 && left > 0; ++b) {
            int base = ((first_bin + b) % u_bins) * u_ranks;
            int below = base + key.y;
            for (int k = first_at_least(cell.x, end, base); k < end && left > 0; ++k) {
                ivec2 other = TABLE_ROW(u_keys, k).xy;
                if (other.x >= below) break;
                --left;
                if (other.y == key.z) continue;
                vec4 step = TABLE_ROW(u_steps, k);
                vec4 unit = TABLE_ROW(u_units, k);
                precise vec2 rel = me.xy - step.xy;
                precise float t = clamp((rel.x * step.z + rel.y * step.w) * unit.z, 0.0, 1.0);
                precise float gx = rel.x - t * step.z;
                precise float gy = rel.y - t * step.w;
                precise float gap = gx * gx + gy * gy;
                precise float turn = abs(me.z * unit.y - me.w * unit.x);
                if (gap <= u_distance2 && turn <= u_sin_limit) {
                    found = 1;
                    break;
                }
            }
        }
    }
    drop[l] = found;
}

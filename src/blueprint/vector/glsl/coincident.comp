// Samples lying on another line of lower rank, for vector/occlusion/coincident.py, which is
// the reference: one invocation per live sample walks the stretches in the 3 x 3 cells around
// it, each cell's stretches sorted by rank, up to its own rank, and tells whether one of
// another line passes within the distance and runs within the angle. The arithmetic is
// NumPy's, in single precision, operation by operation (precise: nothing fused), so the
// answers are the same.
#include "table.glsl"

layout(local_size_x = 64) in;

// live samples: pixel x, y and the direction of their line there x, y; cell, rank, line
layout(std430, binding = 0) readonly buffer Live { vec4 live[]; };
layout(std430, binding = 1) readonly buffer LiveKeys { ivec4 live_keys[]; };
layout(std430, binding = 2) writeonly buffer Drop { int drop[]; };
// tables (gpu/tables.py) of the stretches in cell order: start pixel x, y and the step to the
// next sample x, y; the step's unit vector x, y and 1 / its length squared; rank, line; and
// of the cells: their first stretch, their stretches
uniform sampler2D u_steps;
uniform sampler2D u_units;
uniform isampler2D u_keys;
uniform isampler2D u_cells;

uniform int u_count;        // live samples
uniform int u_span;         // cells a row
uniform float u_distance2;  // the distance squared, as NumPy compares it (single precision)
uniform float u_sin_limit;  // the largest single below the sine of the angle

void main() {
    int l = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (l >= u_count) return;
    vec4 me = live[l];
    ivec4 key = live_keys[l];
    int found = 0;
    for (int n = 0; n < 9 && found == 0; ++n) {
        int probe = key.x + (n / 3 - 1) * u_span + (n % 3 - 1);  // the grid's margin keeps it inside
        ivec2 cell = TABLE_ROW(u_cells, probe).xy;
        int start = cell.x;
        int end = start + cell.y;
        for (int k = start; k < end; ++k) {
            ivec2 other = TABLE_ROW(u_keys, k).xy;
            if (other.x >= key.y) break;
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
    drop[l] = found;
}

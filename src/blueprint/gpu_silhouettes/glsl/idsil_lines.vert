// Object-space silhouette and border edges found on the GPU, one point per edge record
// (blueprint.silhouette.edgerecords). Each face's facing is decided here from its corners, by
// the CPU method's test (classify_edges): the face normal, oriented by the record's sign,
// against the direction to the eye. An edge between a front and a back face, or with one face,
// goes on to the geometry shader (idsil_lines.geom) as its projected segment; any other edge
// stops here, so the per-edge work is done once, not once per corner of a quad.
uniform sampler2D u_corners;  // RGB32F, corner i at (i % 4096, i / 4096)
uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec3 u_eye;           // perspective: the eye in model coordinates
uniform vec3 u_toward;        // orthographic: the direction towards the camera
uniform bool u_ortho;
uniform vec2 u_size;          // viewport in pixels

in ivec4 in_edge;             // (corner0, corner1, face_a, face_b): see edgerecords.py

out vec4 v_ends;              // the segment's ends in window pixels
out vec2 v_depth;             // and their window depths
out float v_drawn;            // 1 where the edge is drawn

// clipped segments keep w at least this, as classify_edges does
const float MIN_W = 1e-12;

vec3 corner(int i) {
    return texelFetch(u_corners, ivec2(i & 4095, i >> 12), 0).xyz;
}

// +1 front-facing, -1 back-facing, 0 degenerate (a zero normal faces neither way); a face seen
// exactly edge-on counts as back-facing, as on the CPU (an orthographic view along a wall)
float facing(int code) {
    int f = abs(code) - 1;
    vec3 p0 = corner(3 * f);
    vec3 p1 = corner(3 * f + 1);
    vec3 p2 = corner(3 * f + 2);
    vec3 n = cross(p1 - p0, p2 - p0) * float(sign(code));
    float longest2 = max(max(dot(p1 - p0, p1 - p0), dot(p2 - p1, p2 - p1)), dot(p0 - p2, p0 - p2));
    if (length(n) <= 1e-12 * longest2) {
        return 0.0;
    }
    return dot(n, u_ortho ? u_toward : u_eye - p0) > 0.0 ? 1.0 : -1.0;
}

bool drawn() {
    if (in_edge.w == 0) {
        return true;  // a border
    }
    return facing(in_edge.z) * facing(in_edge.w) < 0.0;
}

// the part of a clip-space segment where d (linear in clip coordinates) is >= 0
bool clip_to(inout vec4 a, inout vec4 b, float da, float db) {
    if (da < 0.0 && db < 0.0) {
        return false;
    }
    if (da < 0.0) {
        a += (da / (da - db)) * (b - a);
    } else if (db < 0.0) {
        b += (db / (db - da)) * (a - b);
    }
    return true;
}

void main() {
    v_drawn = 0.0;
    v_ends = vec4(0.0);
    v_depth = vec2(0.0);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
    if (!drawn()) {
        return;
    }
    mat4 to_clip = u_projection * u_view;
    vec4 a = to_clip * vec4(corner(in_edge.x), 1.0);
    vec4 b = to_clip * vec4(corner(in_edge.y), 1.0);
    if (!clip_to(a, b, a.z + a.w, b.z + b.w) || !clip_to(a, b, a.w - MIN_W, b.w - MIN_W)) {
        return;
    }
    vec3 na = a.xyz / a.w;
    vec3 nb = b.xyz / b.w;
    v_ends = vec4((na.xy * 0.5 + 0.5) * u_size, (nb.xy * 0.5 + 0.5) * u_size);
    v_depth = vec2(na.z, nb.z) * 0.5 + 0.5;
    v_drawn = 1.0;
}

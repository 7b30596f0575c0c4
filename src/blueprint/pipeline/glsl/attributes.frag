// Attribute pass. Every face is drawn without a depth test; a fragment writes only where the
// layer's G-buffer says its face is the surface there (same face index, depth < 1), so the
// attributes belong to exactly the surface the peel kept. With CLEAR it is a full-screen pass
// that writes the "no surface" values. Each OUT_* define is a colour location, or -1 if unused.
#if !CLEAR
#include "fragment_depth.glsl"
uniform sampler2D u_layer_depth;
uniform isampler2D u_ids;        // (face + 1, part + 1) of the layer
uniform int u_layer;
uniform vec3 u_bounds_lo;
uniform vec3 u_bounds_size;

in vec3 v_model;
in vec3 v_eye;
flat in vec3 v_normal;
flat in int v_first_face;  // the instance's (attributes.vert)
#endif

#if OUT_LINEAR_DEPTH >= 0
layout(location = OUT_LINEAR_DEPTH) out vec4 o_linear_depth;
#endif
#if OUT_POSITION >= 0
layout(location = OUT_POSITION) out vec4 o_position;
#endif
#if OUT_UV >= 0
layout(location = OUT_UV) out vec4 o_uv;
#endif
#if OUT_BASE_COLOR >= 0
layout(location = OUT_BASE_COLOR) out vec4 o_base_color;
#endif
#if OUT_TRIANGLE >= 0
layout(location = OUT_TRIANGLE) out ivec4 o_triangle;
#endif
#if OUT_PART >= 0
layout(location = OUT_PART) out ivec4 o_part;
#endif
#if OUT_LAYER >= 0
layout(location = OUT_LAYER) out ivec4 o_layer;
#endif

// a colour per part: golden-ratio hues at saturation 0.45, value 0.9
vec3 part_color(int part) {
    float h = fract(float(part) * 0.61803398875);
    vec3 p = abs(fract(vec3(h) + vec3(1.0, 2.0 / 3.0, 1.0 / 3.0)) * 6.0 - 3.0);
    return 0.9 * mix(vec3(1.0), clamp(p - 1.0, 0.0, 1.0), 0.45);
}

void main() {
#if CLEAR
    int face = -1;
    int part = -1;
    int layer = -1;
    float linear_depth = 0.0;
    vec4 position = vec4(0.0);
    vec2 uv = vec2(0.0);
    vec4 base_color = vec4(0.0);
#else
    // where the peel's depths are taken at the pixel centre, so are the attributes
    vec3 model = at_centre(v_model);
    vec3 eye = at_centre(v_eye);
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 ids = texelFetch(u_ids, p, 0).xy;
    // (the isnan tests keep in_normal in the program when uv is not asked for, so the mesh's
    // vertex layout always fits, and the steps to the centre before the discard)
    if (isnan(model.x + eye.z) || texelFetch(u_layer_depth, p, 0).r >= 1.0 || ids.x - 1 != v_first_face + gl_PrimitiveID
        || isnan(v_normal.x)) {
        discard;
    }
    int face = v_first_face + gl_PrimitiveID;
    int part = ids.y - 1;
    int layer = u_layer;
    float linear_depth = -eye.z;
    vec4 position = vec4(model, 1.0);
    // box projection of the model's bounds onto the plane the face most nearly lies in
    vec3 t = (model - u_bounds_lo) / u_bounds_size;
    vec3 a = abs(v_normal);
    vec2 uv = a.x >= a.y && a.x >= a.z ? t.yz : (a.y >= a.z ? t.xz : t.xy);
    vec4 base_color = vec4(part_color(part), 1.0);
#endif
#if OUT_LINEAR_DEPTH >= 0
    o_linear_depth = vec4(linear_depth, 0.0, 0.0, 1.0);
#endif
#if OUT_POSITION >= 0
    o_position = position;
#endif
#if OUT_UV >= 0
    o_uv = vec4(uv, 0.0, 1.0);
#endif
#if OUT_BASE_COLOR >= 0
    o_base_color = base_color;
#endif
#if OUT_TRIANGLE >= 0
    o_triangle = ivec4(face);
#endif
#if OUT_PART >= 0
    o_part = ivec4(part);
#endif
#if OUT_LAYER >= 0
    o_layer = ivec4(layer);
#endif
}

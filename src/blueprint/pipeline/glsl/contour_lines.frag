// A contour line's ink at a pixel: full within half its width of the segment, fading over the
// next pixel, so that across the line it inks as much as an edge marking the two pixels beside
// a discontinuity, anti-aliased. Blended by the maximum into the edge map.
flat in vec4 v_segment;
uniform float u_half;  // half the line's width, target pixels
uniform float u_ink;   // its layer's share of the ink (edges.glsl's u_hidden_ink)
out vec4 o_value;

void main() {
    vec2 a = v_segment.xy;
    vec2 ab = v_segment.zw - a;
    vec2 p = gl_FragCoord.xy;
    float t = clamp(dot(p - a, ab) / max(dot(ab, ab), 1e-12), 0.0, 1.0);
    float d = length(p - a - t * ab);
    o_value = vec4(clamp(u_half + 0.5 - d, 0.0, 1.0) * u_ink);
}

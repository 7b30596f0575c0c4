// Line widths by layer: hidden lines (layers >= 1 of a per-layer pass) are u_hidden_width of the
// visible ones' width (ISO 128 draws hidden lines narrow, visible ones wide). An edge map marks
// lines 2 pixels wide (both sides of a discontinuity), which a radius r widens to 2 + 2r; a
// line narrower than that keeps its share of the ink instead (after the box filter a thin line
// is a fainter one), so any width can be asked for.
uniform float u_radius;        // widening of layer 0's lines, pixels
uniform float u_hidden_width;  // width of the other layers' lines over layer 0's

// (radius, ink factor) of layer ``layer``'s lines
vec2 layer_width(int layer) {
    if (layer == 0) {
        return vec2(u_radius, 1.0);
    }
    float r = u_hidden_width * (1.0 + u_radius) - 1.0;
    return r >= 0.0 ? vec2(r, 1.0) : vec2(0.0, 1.0 + r);
}

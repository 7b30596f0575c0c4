// Contour lines drawn into a layer's edge map (pipeline/contours.py): each segment a quad that
// holds it with its width and a pixel to spare, its ends passed on whole to the fragments.
in vec2 in_corner;   // the quad's corner, target pixels (x right, y up)
in vec4 in_segment;  // the segment's ends a (xy) and b (zw), target pixels
uniform vec2 u_target;
flat out vec4 v_segment;

void main() {
    v_segment = in_segment;
    gl_Position = vec4(in_corner / u_target * 2.0 - 1.0, 0.0, 1.0);
}

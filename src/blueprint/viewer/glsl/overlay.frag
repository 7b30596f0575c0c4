// The heads-up overlay (straight alpha) alone, blended over a drawing copied to the window:
// what present.frag draws over the drawing, for the rows the overlay covers.
uniform sampler2D u_overlay;

out vec4 o_color;

void main() {
    o_color = texelFetch(u_overlay, ivec2(gl_FragCoord.xy), 0);
}

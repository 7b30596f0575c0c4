// The viewer's frame: the image the renderer returned (with the heads-up lines drawn on the
// CPU), uploaded as a texture of the window's size and copied pixel for pixel to the window.
uniform sampler2D u_image;

out vec4 o_color;

void main() {
    o_color = vec4(texelFetch(u_image, ivec2(gl_FragCoord.xy), 0).rgb, 1.0);
}

// The viewer's frame: the drawing (straight alpha, or premultiplied where it came from the
// renderer's own target) over the backdrop, scaled to the window (bilinear: a moving frame may
// be smaller; a full-size drawing, SAME_SIZE, is fetched pixel for pixel, what bilinear
// filtering gives at texel centres, which llvmpipe paid for all the same), then the heads-up
// overlay (straight alpha) over that.
uniform sampler2D u_picture;
uniform sampler2D u_overlay;
uniform vec2 u_window;
uniform vec3 u_backdrop;
uniform bool u_premultiplied;

out vec4 o_color;

void main() {
#if SAME_SIZE
    vec4 picture = texelFetch(u_picture, ivec2(gl_FragCoord.xy), 0);
#else
    vec4 picture = texture(u_picture, gl_FragCoord.xy / u_window);
#endif
    vec3 color = u_premultiplied ? u_backdrop * (1.0 - picture.a) + picture.rgb
                                 : mix(u_backdrop, picture.rgb, picture.a);
    vec4 overlay = texelFetch(u_overlay, ivec2(gl_FragCoord.xy), 0);
    o_color = vec4(mix(color, overlay.rgb, overlay.a), 1.0);
}

// The window depth of a geometry pass's fragment. Where the driver takes it from the plane
// through the triangle's corners as snapped to its sub-pixel grid (EXACT_DEPTH: the device's
// snapped_depth), coincident faces of one part with different corners get depths up
// to the slope times the snap apart, past the peel's tolerance on steep faces, and peel as two
// layers. The rasteriser's depth at the pixel centre is the true plane's at the point its
// snapped weights make of the true corners: the interpolated clip position (kept as x, y, w;
// clipping makes new corners of clip positions too), whose window position lies within the
// snap of the centre. Moved from there along the plane to the centre (window depth is affine
// in window position on a plane), the depth is the same for every face of the plane.
#if EXACT_DEPTH
in vec3 v_clip;
uniform vec2 u_target;  // the target's size in pixels: the viewport

// from where the rasteriser's weights put the fragment to the pixel centre, in pixels. The
// steps below take the value's change a pixel along x and y on the snapped triangle for its
// change on the true one: off by the snap over the triangle's size, of a step itself within
// the snap (on a sliver 1/20 px high, 2e-4 px's worth of the slope against 2e-3 uncorrected).
vec2 centre_offset() {
    return gl_FragCoord.xy - u_target * (0.5 + 0.5 * v_clip.xy / v_clip.z);
}

float fragment_depth() {
    float z = gl_FragCoord.z;
    vec2 off = centre_offset();
    return z + dFdx(z) * off.x + dFdy(z) * off.y;
}

// an interpolated attribute at the pixel centre, as the depth is: it and 1/w are affine in
// window position (a value interpolated in perspective is not: on a face seen at a grazing
// angle a step of its own was a quarter off), so both are stepped and divided. Taken before
// any discard, and used in deciding it, as derivatives must be.
vec3 at_centre(vec3 v) {
    vec2 off = centre_offset();
    float q = 1.0 / v_clip.z;
    vec3 p = v * q;
    return (p + dFdx(p) * off.x + dFdy(p) * off.y) / (q + dFdx(q) * off.x + dFdy(q) * off.y);
}
#else
float fragment_depth() {
    return gl_FragCoord.z;
}

vec3 at_centre(vec3 v) {
    return v;
}
#endif

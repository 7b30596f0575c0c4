// Lines of several layers at one sample: the strongest wins. Coincident edges of different
// layers (a hole's near and far rims seen edge-on) are one line on paper, so their inks must
// not add up into something darker than any of them; each line's opacity is its coverage
// times its ink's, and the union keeps the largest. The front line takes its own coverage in
// its own ink, the lines behind fill what is left up to the maximum in their mixed ink, which
// keeps the result continuous in every coverage (anti-aliased rims stay smooth).

// ``lines`` premultiplied, the union so far (the layers behind); a line of ``ink`` at
// opacity ``a`` laid in front of it
vec4 strongest(vec4 lines, vec3 ink, float a) {
    float total = max(lines.a, a);
    vec3 behind = lines.a > 0.0 ? lines.rgb * ((total - a) / lines.a) : vec3(0.0);
    return vec4(ink * a + behind, total);
}

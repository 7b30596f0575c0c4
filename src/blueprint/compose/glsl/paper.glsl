// Paper with an optional drafting grid (minor lines every u_grid pixels, major every fifth).
uniform vec4 u_paper;
uniform vec4 u_grid_color;
uniform float u_grid;

float grid_line(vec2 frag, float spacing) {
    vec2 d = abs(mod(frag - 0.5 + spacing * 0.5, spacing) - spacing * 0.5);
    return 1.0 - clamp(min(d.x, d.y), 0.0, 1.0);
}

// premultiplied paper colour at a pixel centre
vec4 paper_color(vec2 frag) {
    vec4 color = u_paper;
    if (u_grid > 0.0) {
        float line = max(0.45 * grid_line(frag, u_grid), grid_line(frag, u_grid * 5.0));
        color.rgb = mix(color.rgb, u_grid_color.rgb, line * u_grid_color.a);
    }
    return vec4(color.rgb * color.a, color.a);
}

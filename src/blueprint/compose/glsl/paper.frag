// Paper with an optional drafting grid (minor lines every u_grid pixels, major every fifth).
uniform vec4 u_paper;
uniform vec4 u_grid_color;
uniform float u_grid;

out vec4 o_color;

float grid_line(float spacing) {
    vec2 d = abs(mod(gl_FragCoord.xy - 0.5 + spacing * 0.5, spacing) - spacing * 0.5);
    return 1.0 - clamp(min(d.x, d.y), 0.0, 1.0);
}

void main() {
    vec4 color = u_paper;
    if (u_grid > 0.0) {
        float line = max(0.45 * grid_line(u_grid), grid_line(u_grid * 5.0));
        color.rgb = mix(color.rgb, u_grid_color.rgb, line * u_grid_color.a);
    }
    o_color = vec4(color.rgb * color.a, color.a);
}

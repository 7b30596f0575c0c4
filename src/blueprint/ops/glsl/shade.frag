// Deferred Lambert shading of the shaded parts' front surface (a headlight plus ambient) in the
// style's shade colour, premultiplied by the shading's opacity; transparent where those parts
// are absent.
uniform sampler2D u_depth;
uniform sampler2D u_normal;
uniform vec4 u_shade_ink;    // the style's shade colour (set by the executor)
uniform float u_opacity;

out vec4 o_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (texelFetch(u_depth, p, 0).r >= 1.0) {
        o_color = vec4(0.0);
        return;
    }
    vec3 n = texelFetch(u_normal, p, 0).xyz;
    float light = 0.35 + 0.65 * clamp(n.z, 0.0, 1.0);
    o_color = vec4(u_shade_ink.rgb * light * u_opacity, u_opacity);
}

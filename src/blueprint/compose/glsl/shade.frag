// Deferred Lambert shading of the shaded parts' front surface (a headlight plus ambient),
// premultiplied by the shading's opacity; transparent where those parts are absent.
uniform sampler2D u_depth;
uniform sampler2D u_normal;
uniform vec4 u_color;        // straight colour, alpha = opacity (1: opaque)

out vec4 o_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (texelFetch(u_depth, p, 0).r >= 1.0) {
        o_color = vec4(0.0);
        return;
    }
    vec3 n = texelFetch(u_normal, p, 0).xyz;
    float light = 0.35 + 0.65 * clamp(n.z, 0.0, 1.0);
    o_color = vec4(u_color.rgb * light * u_color.a, u_color.a);
}

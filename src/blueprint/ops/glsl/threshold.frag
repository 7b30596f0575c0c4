// Binary threshold of the colour channels: 1 at or above u_level, 0 below (alpha kept).
uniform sampler2D u_source;
uniform float u_level;
uniform bool u_invert;

out vec4 o_value;

void main() {
    vec4 v = texelFetch(u_source, ivec2(gl_FragCoord.xy), 0);
    vec3 b = step(vec3(u_level), v.rgb);
    o_value = vec4(u_invert ? 1.0 - b : b, v.a);
}

// 1 - value in the colour channels, alpha kept.
uniform sampler2D u_source;

out vec4 o_value;

void main() {
    vec4 v = texelFetch(u_source, ivec2(gl_FragCoord.xy), 0);
    o_value = vec4(1.0 - v.rgb, v.a);
}

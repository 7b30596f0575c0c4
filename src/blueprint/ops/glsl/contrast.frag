// (value - 0.5) * contrast + 0.5 + brightness in the colour channels, alpha kept.
uniform sampler2D u_source;
uniform float u_contrast;
uniform float u_brightness;

out vec4 o_value;

void main() {
    vec4 v = texelFetch(u_source, ivec2(gl_FragCoord.xy), 0);
    o_value = vec4((v.rgb - 0.5) * u_contrast + 0.5 + u_brightness, v.a);
}

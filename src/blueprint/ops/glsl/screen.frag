// Halftone screening: 1 where the intensity exceeds a dot screen of period u_period pixels
// turned by u_angle degrees, t = 0.5 + 0.25 (cos(2 pi u / period) + cos(2 pi v / period)).
// Intensity is the luminance of an RGB(A) source, or the only channel of a one-channel one.
uniform sampler2D u_source;
uniform int u_source_components;
uniform float u_period;
uniform float u_angle;

out vec4 o_value;

void main() {
    vec2 p = gl_FragCoord.xy;
    vec4 s = texelFetch(u_source, ivec2(p), 0);
    float intensity = u_source_components >= 3 ? dot(s.rgb, vec3(0.299, 0.587, 0.114)) : s.r;
    float a = radians(u_angle);
    float u = cos(a) * p.x + sin(a) * p.y;
    float v = -sin(a) * p.x + cos(a) * p.y;
    float k = 6.28318530718 / u_period;
    float t = 0.5 + 0.25 * (cos(k * u) + cos(k * v));
    float e = float(intensity > t);
    o_value = vec4(e, e, e, 1.0);
}

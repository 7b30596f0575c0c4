// Deferred shading inputs: eye-space normal, window depth (coverage) and base colour.
uniform sampler2D u_normal;
uniform sampler2D u_depth;
uniform sampler2D u_color;
uniform vec3 u_light;  // unit direction towards the light, eye space
uniform float u_ambient;
uniform float u_background;  // grey where there is no surface; 0: transparent

vec4 background() {
    return u_background > 0.0 ? vec4(vec3(u_background), 1.0) : vec4(0.0);
}

// max(n.l, 0) at p, or -1 where there is no surface
float diffuse(ivec2 p) {
    if (texelFetch(u_depth, p, 0).r >= 1.0) {
        return -1.0;
    }
    vec3 n = texelFetch(u_normal, p, 0).xyz;
    float len = length(n);
    return len > 0.0 ? max(dot(n / len, u_light), 0.0) : 0.0;
}

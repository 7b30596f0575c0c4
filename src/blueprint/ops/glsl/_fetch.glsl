// Texel fetch clamped to the image: outside counts as more of the edge (no frame lines).
vec4 fetch(sampler2D s, ivec2 p) {
    return texelFetch(s, clamp(p, ivec2(0), textureSize(s, 0) - 1), 0);
}

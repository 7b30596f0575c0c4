// One level's contour lines (pipeline/contours.py), drawn into a map of their own, merged into
// that layer's slice of the compute form's array of edge maps by the maximum, as the lines
// blend into a layer's own map in the fragment form.
layout(local_size_x = 8, local_size_y = 8) in;

layout(r8, binding = 0) uniform image2DArray u_maps;
uniform sampler2D u_lines;
uniform int u_slice;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(u_maps).xy))) {
        return;
    }
    float line = texelFetch(u_lines, p, 0).r;
    if (line > 0.0) {
        ivec3 at = ivec3(p, u_slice);
        imageStore(u_maps, at, vec4(max(imageLoad(u_maps, at).r, line)));
    }
}

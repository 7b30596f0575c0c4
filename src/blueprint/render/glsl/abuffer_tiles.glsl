// The pixel of a compute pass over listed tiles only (a software rasteriser pays for every
// group it runs, empty or not): the first u_groups / (TILES / 8)^2 entries of u_tile_list,
// tiles of TILES x TILES pixels packed as x | y << 16, AB_ROW a row of the image, in groups of
// 8 x 8 dispatched in rows of ROW (a define); (-1, -1) past the listed groups. The including
// pass binds the list at TILE_LIST_BINDING.
layout(binding = TILE_LIST_BINDING, r32ui) readonly uniform uimage2D u_tile_list;
uniform uint u_groups;

ivec2 listed_pixel() {
    uint g = gl_WorkGroupID.y * uint(ROW) + gl_WorkGroupID.x;
    const uint per_tile = uint((TILES / 8) * (TILES / 8));
    uint listed = g / per_tile;
    uint entry = imageLoad(u_tile_list, ivec2(int(listed % uint(AB_ROW)), int(listed / uint(AB_ROW)))).x;
    uint sub = g % per_tile;
    ivec2 tile = ivec2(entry & 0xffffu, entry >> 16);
    ivec2 corner = tile * TILES + ivec2(sub % uint(TILES / 8), sub / uint(TILES / 8)) * 8;
    return g < u_groups ? corner + ivec2(gl_LocalInvocationID.xy) : ivec2(-1);
}

// Where a voxel of a sparse volume's grid is stored (issue #39, core/volume/brick_layout.h): the
// grids are atlases of kBrickSize³ bricks, and a table gives each brick of the box its atlas brick
// (inactive bricks: the background brick, at the atlas's origin). Needs the including kernel's
// uniform block `u` to have `sparseOffset` (xyz: where voxel 0 lies in its brick).
layout(binding = kUnitBrickTable) uniform usampler3D s_brickTable;

// The atlas brick of brick b (r32ui: x | y << kAtlasBits | z << 2 kAtlasBits).
ivec3 atlasBrick(ivec3 b) {
    uint e = texelFetch(s_brickTable, b, 0).r;
    uint mask = (1u << kAtlasBits) - 1u;
    return ivec3(e & mask, (e >> kAtlasBits) & mask, e >> (2 * kAtlasBits));
}

// Where voxel v of the box is stored.
ivec3 storedTexel(ivec3 v) {
    ivec3 q = v + u.sparseOffset.xyz;
    return atlasBrick(q / kBrickSize) * kBrickSize + q % kBrickSize;
}

// Brick occupancy for empty-space skipping: the largest extinction (any channel) over each
// kBrickSize³ brick plus a one-voxel apron — every voxel a trilinear sample inside the brick reads.
// A sparse volume's inactive bricks hold the background (zero extinction): an occupancy brick whose
// apron touches only inactive bricks is empty without reading a voxel.
#include "common/volume.glsl"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;
layout(binding = kImageUnitOut, r32f) uniform writeonly image3D img_occupancy;

void main() {
    ivec3 brick = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(brick, u.brickDims.xyz))) return;
    ivec3 lo = max(brick * kBrickSize - 1, ivec3(0));
    ivec3 hi = min(brick * kBrickSize + kBrickSize, u.dims.xyz - 1);
    float m = 0.0;
#if VOLSTYLE_SPARSE
    ivec3 bLo = (lo + u.sparseOffset.xyz) / kBrickSize, bHi = (hi + u.sparseOffset.xyz) / kBrickSize;
    bool any = false;
    for (int z = bLo.z; z <= bHi.z; ++z)
        for (int y = bLo.y; y <= bHi.y; ++y)
            for (int x = bLo.x; x <= bHi.x; ++x) any = any || texelFetch(s_brickTable, ivec3(x, y, z), 0).r != 0u;
    if (!any) {
        imageStore(img_occupancy, brick, vec4(0.0));
        return;
    }
#endif
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) m = max(m, max3(voxelAt(s_extinction, ivec3(x, y, z))));
    imageStore(img_occupancy, brick, vec4(m));
}

// Brick occupancy for empty-space skipping: the largest extinction (any channel) over each
// kBrickSize³ brick plus a one-voxel apron — every voxel a trilinear sample inside the brick reads.
#include "common/params.glsl"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;
layout(binding = kUnitExtinction) uniform sampler3D s_extinction;
layout(binding = kImageUnitOut, r32f) uniform writeonly image3D img_occupancy;

void main() {
    ivec3 brick = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(brick, u.brickDims.xyz))) return;
    ivec3 lo = max(brick * kBrickSize - 1, ivec3(0));
    ivec3 hi = min(brick * kBrickSize + kBrickSize, u.dims.xyz - 1);
    float m = 0.0;
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) m = max(m, max3(texelFetch(s_extinction, ivec3(x, y, z), 0).rgb));
    imageStore(img_occupancy, brick, vec4(m));
}

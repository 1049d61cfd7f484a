// The bricks of a sparse volume's stylizer medium (issue #39): per kBrickSize³ brick of the
// block-mean σt grid (stylize_extinction_mean.comp), its largest value over the brick and a
// one-voxel apron — every voxel a trilinear lookup inside the brick reads — as occupancy.comp
// gives a dense volume's bricks. stylize.comp skips a brick whose entry is 0.
#include "layout.h"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;

layout(binding = kUnitStylizeDensity) uniform sampler3D s_sigma;
layout(r32f, binding = kImageUnitOut) writeonly uniform image3D o_occupancy;

void main() {
    ivec3 n = textureSize(s_sigma, 0);
    ivec3 brick = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(brick * kBrickSize, n))) return;
    ivec3 lo = max(brick * kBrickSize - 1, ivec3(0)), hi = min(brick * kBrickSize + kBrickSize, n - 1);
    float m = 0.0;
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) m = max(m, texelFetch(s_sigma, ivec3(x, y, z), 0).r);
    imageStore(o_occupancy, brick, vec4(m));
}

// The stylizer's σt grid from the session's volume on the GPU (issue #36): the mean of its RGB
// extinction per voxel, as one channel (r32f). Made once per extinction version and kept in the
// device's cache. The march could read the RGB texture itself, but on a CPU rasterizer its three
// times larger footprint made a 960×540 frame through the built-in 64³ cloud 10–15% slower
// (docs/BENCHMARKS.md, issue #36); one channel matches the old frame time.
//
// A sparse volume (VOLSTYLE_SPARSE, issue #39) gives the mean over blocks of f³ voxels instead
// (f = m.dims.w, chosen so the grid stays within the stylizer's budget; f = 1 gives each voxel's
// mean exactly as the dense kernel does). The block is walked brick by brick of the volume's
// layout: a brick that is not stored counts as the background (slot 0) without a voxel read, so
// the cost follows the active voxels, not the box.
#include "layout.h"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;

layout(binding = kUnitStylizeDensity) uniform sampler3D s_extinctionRgb;
layout(r32f, binding = kImageUnitOut) writeonly uniform image3D o_sigma;

float meanOf(vec3 e) { return (e.r + e.g + e.b) / 3.0; }

#if VOLSTYLE_SPARSE
layout(std140, binding = kBindingParams) uniform b_StylizeMediumParams {
    StylizeMediumParams u;
};
#include "common/sparse_grid.glsl"

void main() {
    ivec3 n = u.dims.xyz;
    int f = u.dims.w;
    ivec3 r = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(r * f, n))) return;
    ivec3 lo = r * f, hi = min(lo + f, n) - 1;  // the block's voxels, inclusive
    ivec3 bLo = (lo + u.sparseOffset.xyz) / kBrickSize, bHi = (hi + u.sparseOffset.xyz) / kBrickSize;
    float background = meanOf(texelFetch(s_extinctionRgb, ivec3(0), 0).rgb);  // slot 0: the background brick
    float sum = 0.0;
    for (int bz = bLo.z; bz <= bHi.z; ++bz)
        for (int by = bLo.y; by <= bHi.y; ++by)
            for (int bx = bLo.x; bx <= bHi.x; ++bx) {
                ivec3 b = ivec3(bx, by, bz);
                ivec3 first = b * kBrickSize - u.sparseOffset.xyz;  // the brick's voxel 0 in the box
                ivec3 vLo = max(lo, first), vHi = min(hi, first + kBrickSize - 1);
                if (texelFetch(s_brickTable, b, 0).r == 0u) {
                    ivec3 count = vHi - vLo + 1;
                    sum += background * float(count.x * count.y * count.z);
                    continue;
                }
                ivec3 base = atlasBrick(b) * kBrickSize - first;  // voxel v is stored at base + v
                for (int z = vLo.z; z <= vHi.z; ++z)
                    for (int y = vLo.y; y <= vHi.y; ++y)
                        for (int x = vLo.x; x <= vHi.x; ++x) sum += meanOf(texelFetch(s_extinctionRgb, base + ivec3(x, y, z), 0).rgb);
            }
    ivec3 count = hi - lo + 1;
    imageStore(o_sigma, r, vec4(sum / float(count.x * count.y * count.z)));
}
#else
void main() {
    ivec3 n = textureSize(s_extinctionRgb, 0);
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, n))) return;
    imageStore(o_sigma, v, vec4(meanOf(texelFetch(s_extinctionRgb, v, 0).rgb)));
}
#endif

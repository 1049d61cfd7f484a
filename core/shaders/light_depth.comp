// Optical depth from every voxel centre toward light u.imageSize.z, marched with the same
// segments and skipping as view rays. Recomputed only when extinction or the light changes.
#include "common/march.glsl"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;
layout(binding = kImageUnitOut, rgba32f) uniform writeonly image3D img_lightDepth;

// Past this optical depth the light is e^-64 ≈ 1.6e-28: nothing left to attenuate.
const float kOpaqueDepth = 64.0;

void main() {
    ivec3 voxel = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(voxel, u.dims.xyz))) return;

    // Voxels in empty bricks are only ever read where σ = 0 (see skipEmptyBricks), so skip them.
    ivec3 brick = voxel / kBrickSize;
    vec3 depth = vec3(0.0);
    if (texelFetch(s_occupancy, brick, 0).r > 0.0) {
        vec3 o = vec3(voxel);
        vec3 d = mat3(u.indexFromWorld) * u.lightDirection[u.imageSize.z].xyz;
        vec2 range = vec2(0.0, intersectVolumeBox(o, d).y);
        if (range.y > 0.0) {
            Segments seg = makeSegments(range, d);
            for (int i = 0; i < seg.count;) {
                int next = skipEmptyBricks(i, seg, o, d);
                if (next != i) {
                    i = next;
                    continue;
                }
                depth += fetchTrilinear(s_extinction, stencilAt(o + segmentMidpoint(seg, i) * d)) * seg.dt;
                ++i;
                if (min(depth.r, min(depth.g, depth.b)) > kOpaqueDepth) break;
            }
        }
    }
    imageStore(img_lightDepth, voxel, vec4(depth, 0.0));
}

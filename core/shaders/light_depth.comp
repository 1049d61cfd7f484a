// Optical depth from every voxel centre toward light u.lightKernel.x, marched with the same
// segments and skipping as view rays. Recomputed only when extinction or the light changes.
#include "common/march.glsl"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;
layout(binding = kImageUnitOut, rgba32f) uniform writeonly image3D img_lightDepth;

// Past this optical depth the light is e^-64 ≈ 1.6e-28: nothing left to attenuate.
const float kOpaqueDepth = 64.0;

void main() {
    ivec3 voxel = ivec3(gl_GlobalInvocationID) + u.dispatchOffset.xyz;  // chunked_dispatch.h
    if (any(greaterThanEqual(voxel, u.dims.xyz))) return;

    // A voxel's depth is read only by samples whose trilinear stencil holds it; the rest of such a
    // stencil lies within one voxel of it, so if that 3³ neighbourhood has no extinction every
    // reader has σ = 0 and multiplies the depth by nothing. Skip those voxels (exactly), first by
    // brick (the brick's apron covers the neighbourhood), then voxel by voxel.
    vec3 depth = vec3(0.0);
    bool isRead = texelFetch(s_occupancy, voxel / kBrickSize, 0).r > 0.0;
    if (isRead) {
        float neighbourhood = 0.0;
        ivec3 lo = max(voxel - 1, ivec3(0)), hi = min(voxel + 1, u.dims.xyz - 1);
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x)
                    neighbourhood = max(neighbourhood, max3(texelFetch(s_extinction, ivec3(x, y, z), 0).rgb));
        isRead = neighbourhood > 0.0;
    }
    if (isRead) {
        vec3 o = vec3(voxel);  // march from the voxel centre toward the light
        vec3 d = mat3(u.indexFromWorld) * u.lightDirection[u.lightKernel.x].xyz;
        vec2 range = vec2(0.0, intersectVolumeBox(o, d).y);
        if (range.y > 0.0) {
            RayMarch m = beginMarch(range, o, d);
            float tMid, dt;
            while (nextSegment(m, true, tMid, dt)) {
                depth += fetchTrilinear(s_extinction, stencilAt(o + tMid * d)) * dt;
                if (min(depth.r, min(depth.g, depth.b)) > kOpaqueDepth) break;
            }
        }
    }
    imageStore(img_lightDepth, voxel, vec4(depth, 0.0));
}

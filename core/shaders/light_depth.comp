// Optical depth toward light u.lightKernel.x on its light-aligned grid (core/render/light_grid.h):
// one invocation per row of nodes, a ray marched once from the light side, writing at every node
// the depth accumulated so far, τ(node c) = τ(node c−1) + ∫ σ over the span between them. Each
// span's part inside the voxels' box is cut into equal segments of at most u.march.x voxels,
// sampled at their midpoints (exact for a constant medium); outside the box σ = 0. O(N) for N
// voxels. Recomputed only when the extinction or the light changes. The texture is cleared to 0
// first: nodes before a row enters the box, and rows that miss it, keep that depth.
#include "common/volume.glsl"

#ifndef VOLSTYLE_GREY_DEPTH
#define VOLSTYLE_GREY_DEPTH 0
#endif

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;
#if VOLSTYLE_GREY_DEPTH
// Grey extinction: one channel (its texture swizzles red into green and blue).
layout(binding = kImageUnitOut, r32f) uniform writeonly image3D img_lightDepth;
#else
layout(binding = kImageUnitOut, rgba32f) uniform writeonly image3D img_lightDepth;
#endif

// Past this optical depth the light is e^-64 ≈ 1.6e-28: nothing left to attenuate.
const float kOpaqueDepth = 64.0;

// The corners of the voxel cell last sampled: a row samples each cell about 1 / u.march.x times
// in a row, so the 8 fetches are shared by those samples (the values fetchTrilinear reads).
struct CellCache {
    ivec3 i0;
    Corners corners;
};

vec3 extinctionAt(inout CellCache cache, vec3 p) {
    Stencil s = stencilAt(p);
    if (s.i0 != cache.i0) {
        cache.i0 = s.i0;
        cache.corners = fetchCorners(s_extinction, s);
    }
    return interpolateCorners(cache.corners, s.f);
}

// Where the ray o + t·d leaves the occupancy brick holding p if that brick is empty (σ = 0
// throughout it, apron included); otherwise -1.
float emptyBrickExit(vec3 p, vec3 o, vec3 invD) {
    ivec3 brick = clamp(ivec3(floor((p + 0.5) / float(kBrickSize))), ivec3(0), u.brickDims.xyz - 1);
    if (texelFetch(s_occupancy, brick, 0).r > 0.0) return -1.0;
    vec3 lo = vec3(brick * kBrickSize) - 0.5, hi = lo + float(kBrickSize);
    vec3 tFar = max((lo - o) * invD, (hi - o) * invD);
    return min(tFar.x, min(tFar.y, tFar.z));
}

void main() {
    ivec2 row = ivec2(gl_GlobalInvocationID.xy) + u.dispatchOffset.xy;  // chunked_dispatch.h
    ivec3 n = u.lightGridDims[u.lightKernel.x].xyz;
    if (row.x >= n.x || row.y >= n.y) return;

    // The row's first node (on the light side) and the index-space step between nodes: the ray is
    // o + t·d with t in nodes.
    vec3 o = (u.indexFromLightGrid * vec4(vec2(row), 0.0, 1.0)).xyz;
    vec3 d = mat3(u.indexFromLightGrid)[2];
    vec3 invD = 1.0 / mix(d, vec3(1e-30), equal(d, vec3(0.0)));
    vec2 inside = intersectVolumeBox(o, d);
    if (inside.x >= inside.y) return;                          // misses the box: depth 0 throughout
    float stepsPerNode = length(d) / u.march.x;               // segments of at most march.x voxels
    float worldPerNode = length(inverse(mat3(u.indexFromWorld)) * d);  // σ is per world unit

    CellCache cache;
    cache.i0 = ivec3(-1);
    vec3 depth = vec3(0.0);
    float skipTo = -1.0;  // samples before this t lie in an empty brick
    for (int c = max(1, int(floor(inside.x)) + 1); c < n.z; ++c) {
        // The span [c−1, c] within the box; nothing to add after the ray leaves it, or once the
        // light is gone.
        float t0 = max(float(c - 1), inside.x), t1 = min(float(c), inside.y);
        if (t1 > t0 && min(depth.r, min(depth.g, depth.b)) <= kOpaqueDepth && skipTo < t1) {
            int count = max(1, int(ceil((t1 - t0) * stepsPerNode)));
            float dt = (t1 - t0) / float(count);
            float span = dt * worldPerNode;  // world length of one segment
            for (int i = 0; i < count; ++i) {
                float t = t0 + (float(i) + 0.5) * dt;
                if (t < skipTo) continue;
                vec3 p = o + t * d;
                float exit = emptyBrickExit(p, o, invD);
                if (exit > t) {
                    skipTo = exit;
                    continue;
                }
                depth += extinctionAt(cache, p) * span;
            }
        }
        imageStore(img_lightDepth, ivec3(row, c), vec4(depth, 0.0));
    }
}

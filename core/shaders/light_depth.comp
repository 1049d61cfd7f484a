// Optical depth toward light u.lightKernel.x on its light-aligned grid (core/render/light_grid.h):
// one invocation per row of nodes, a ray marched once, writing at every node the depth accumulated
// so far, τ(node c) = τ(node c−1) + ∫ σ over the span between them. Each span is cut into equal
// segments of at most 2·u.march.x voxels, sampled at their midpoints (exact for a constant medium).
// O(N) for N voxels. Recomputed only when the extinction or the light changes. Past the voxels'
// box the field is extended (see main()) so that interpolation is right up to the box's faces.
// The texture is cleared to 0 first: nodes no point in the box interpolates from keep it.
#include "common/volume.glsl"
#include "common/ray_box.glsl"

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

// Where the ray o + t·d leaves the occupancy brick holding p if that brick is empty (σ = 0
// throughout it, apron included); otherwise -1e30 (rays reversed toward the light run at
// negative t). p must lie in the voxels' box.
float emptyBrickExit(vec3 p, vec3 o, vec3 invD) {
    ivec3 brick = clamp(ivec3(floor((p + 0.5) / float(kBrickSize))), ivec3(0), u.brickDims.xyz - 1);
    if (texelFetch(s_occupancy, brick, 0).r > 0.0) return -1e30;
    vec3 lo = vec3(brick * kBrickSize) - 0.5, hi = lo + float(kBrickSize);
    vec3 tFar = max((lo - o) * invD, (hi - o) * invD);
    return min(tFar.x, min(tFar.y, tFar.z));
}

bool insideVoxelBox(vec3 p) { return all(greaterThanEqual(p, vec3(-0.5))) && all(lessThanEqual(p, vec3(u.dims.xyz) - 0.5)); }

// ∫ σ over [ta, tb] of the ray o + t·d (t in nodes, ta ≤ tb), in equal segments of at most
// 1 / stepsPerNode nodes sampled at their midpoints (exact for a constant medium), per world unit. σ is
// the clamped field (stencilAt clamps to the edge): outside the box it continues the faces' values.
// Segments in empty bricks inside the box add exactly nothing and are skipped (skipTo: the ray's
// t up to which they are; calls must come in increasing t).
vec3 integrateExtinction(inout CellCache cache, vec3 o, vec3 d, vec3 invD, float ta, float tb, float stepsPerNode,
                         float worldPerNode, inout float skipTo) {
    vec3 sum = vec3(0.0);
    if (!(tb > ta)) return sum;
    int count = max(1, int(ceil((tb - ta) * stepsPerNode)));
    float dt = (tb - ta) / float(count);
    for (int i = 0; i < count; ++i) {
        float t = ta + (float(i) + 0.5) * dt;
        if (t < skipTo) continue;
        vec3 p = o + t * d;
        if (insideVoxelBox(p)) {
            float exit = emptyBrickExit(p, o, invD);
            if (exit > t) {
                skipTo = exit;
                continue;
            }
        }
        sum += extinctionAt(cache, p);
    }
    return sum * (dt * worldPerNode);
}

// Where the row o + t·d crosses the last of the planes of the box's light-side faces (the largest
// near-plane t over the axes it moves along; an axis it runs parallel to has no light-side face),
// clamped to [lo, hi]: a row almost parallel to a face crosses its plane far away.
float lightSideCrossing(vec3 o, vec3 d, float lo, float hi) {
    vec3 boxLo = vec3(-0.5), boxHi = vec3(u.dims.xyz) - 0.5;
    float t = lo;
    for (int a = 0; a < 3; ++a)
        if (abs(d[a]) > 1e-6 * length(d)) t = max(t, ((d[a] > 0.0 ? boxLo[a] : boxHi[a]) - o[a]) / d[a]);
    return min(t, hi);
}

void main() {
    ivec2 row = ivec2(gl_GlobalInvocationID.xy) + u.dispatchOffset.xy;  // chunked_dispatch.h
    ivec3 n = u.lightGridDims[u.lightKernel.x].xyz;
    if (row.x >= n.x || row.y >= n.y) return;

    // The row's first node (on the light side) and the index-space step between nodes: the ray is
    // o + t·d with t in nodes.
    vec3 o = (u.indexFromLightGrid * vec4(vec2(row), 0.0, 1.0)).xyz;
    vec3 d = mat3(u.indexFromLightGrid)[2];
    vec3 invD = safeInverse(d);
    // Segments of at most twice the march step: lightDepthAt marches the first node spans from each
    // sample itself at the step, and what the grid adds further on is smooth enough (issue #34:
    // the same accuracy against the exact light integral, half the build).
    float stepsPerNode = length(d) / (2.0 * u.march.x);
    float worldPerNode = length(inverse(mat3(u.indexFromWorld)) * d);  // σ is per world unit

    // Only nodes that some point in the voxels' box interpolates from are needed: those within a
    // cell diagonal of the box. Rows that pass farther away keep the cleared 0.
    mat3 cell = mat3(u.indexFromLightGrid);
    float reach = length(vec3(length(cell[0]), length(cell[1]), length(cell[2]))) + 1e-3;
    vec2 near = rayBox(o, invD, vec3(-0.5 - reach), vec3(u.dims.xyz) - 0.5 + reach);
    if (near.x >= near.y) return;
    int cFirst = max(0, int(floor(near.x))), cLast = min(n.z - 1, int(ceil(near.y)));

    // The depth field extended past the box, so that interpolating between nodes is right up to
    // its faces (issue #34): τ(x) = ∫ σ from x toward the light up to the planes of the box's
    // light-side faces, σ clamped to the box. A row crosses those planes once, at t* (the box's
    // entry for rows that meet it). Nodes after t* hold ∫_{t*}^{c} σ (inside the box: the light
    // depth itself), nodes before it −∫_{c}^{t*} σ. Outside the box the field so continues linearly
    // across every face, and a constant medium is interpolated exactly everywhere in it. The light
    // depth held 0 on nodes before the entry and on rows missing the box, so points within a node
    // of a face mixed in zeros (a sun-lit slab came out 2–12% too bright).
    float tStar = lightSideCrossing(o, d, float(cFirst - n.z), float(cLast + n.z));
    CellCache cache = emptyCellCache();

    // Nodes after t*, away from the light.
    int c0 = max(cFirst, int(ceil(tStar)));
    float skipTo = -1e30;
    vec3 depth = vec3(0.0);
    if (c0 <= cLast) depth = integrateExtinction(cache, o, d, invD, tStar, float(c0), stepsPerNode, worldPerNode, skipTo);
    for (int c = c0; c <= cLast; ++c) {
        if (c > c0 && min(depth.r, min(depth.g, depth.b)) <= kOpaqueDepth)
            depth += integrateExtinction(cache, o, d, invD, float(c - 1), float(c), stepsPerNode, worldPerNode, skipTo);
        imageStore(img_lightDepth, ivec3(row, c), vec4(depth, 0.0));
    }

    // Nodes before t*, toward the light: the same integral on the reversed ray o − s·d (s = −t),
    // so that skipping still runs forward.
    int c1 = min(cLast, int(ceil(tStar)) - 1);
    skipTo = -1e30;
    if (c1 >= cFirst) depth = -integrateExtinction(cache, o, -d, -invD, -tStar, -float(c1), stepsPerNode, worldPerNode, skipTo);
    for (int c = c1; c >= cFirst; --c) {
        if (c < c1)
            depth -= integrateExtinction(cache, o, -d, -invD, -float(c + 1), -float(c), stepsPerNode, worldPerNode, skipTo);
        imageStore(img_lightDepth, ivec3(row, c), vec4(depth, 0.0));
    }
}

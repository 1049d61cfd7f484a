// Sampling the property grids. Index space: voxel (i,j,k) has its centre at (i,j,k); values are
// trilinear between centres, clamped to the edge within the voxels' box [-0.5, n-0.5]³, and zero
// outside it (the march never samples outside).
//
// Dense volumes store the grids as 3D textures of the box. Sparse ones (VOLSTYLE_SPARSE, issue
// #39) as atlases of kBrickSize³ bricks with a table from brick to atlas brick; inactive bricks
// point at the background brick, so a fetch never branches. Either way a voxel reads the same value.
#include "common/params.glsl"

#ifndef VOLSTYLE_HW_FILTER
#define VOLSTYLE_HW_FILTER 0
#endif
#ifndef VOLSTYLE_SPARSE
#define VOLSTYLE_SPARSE 0
#endif

layout(binding = kUnitExtinction) uniform sampler3D s_extinction;
layout(binding = kUnitOccupancy) uniform sampler3D s_occupancy;

#if VOLSTYLE_SPARSE
#include "common/sparse_grid.glsl"
#else
ivec3 storedTexel(ivec3 v) { return v; }
#endif

// The texel of voxel v of a property grid (`grid`), or texel v of any other texture.
ivec3 texelOf(ivec3 v, bool grid) { return grid ? storedTexel(v) : v; }

// The value of voxel v (inside the box) of a property grid.
vec3 voxelAt(sampler3D grid, ivec3 v) { return texelFetch(grid, storedTexel(v), 0).rgb; }

// The 8-node trilinear stencil of point p on a grid of n nodes (node i at integer i): corners
// i0..i1, weights from f, clamped to the edge.
struct Stencil {
    ivec3 i0;
    ivec3 i1;
    vec3 f;
    vec3 p;
    ivec3 n;
};

Stencil stencilOn(vec3 p, ivec3 n) {
    Stencil s;
    vec3 q = clamp(p, vec3(0.0), vec3(n - 1));
    s.i0 = min(ivec3(floor(q)), n - 1);
    s.i1 = min(s.i0 + 1, n - 1);
    s.f = q - vec3(s.i0);
    s.p = p;
    s.n = n;
    return s;
}

// The stencil of index-space point p on the property grids.
Stencil stencilAt(vec3 p) { return stencilOn(p, u.dims.xyz); }

// The 8 values of a stencil's corners.
struct Corners {
    vec3 c000, c100, c010, c110, c001, c101, c011, c111;
};

// The 8 corners of a stencil on a texture: a property grid (`grid`: through the brick table of a
// sparse volume) or a texture of its own lattice (light depth).
Corners fetchCorners(sampler3D tex, Stencil s, bool grid) {
    Corners c;
    c.c000 = texelFetch(tex, texelOf(ivec3(s.i0.x, s.i0.y, s.i0.z), grid), 0).rgb;
    c.c100 = texelFetch(tex, texelOf(ivec3(s.i1.x, s.i0.y, s.i0.z), grid), 0).rgb;
    c.c010 = texelFetch(tex, texelOf(ivec3(s.i0.x, s.i1.y, s.i0.z), grid), 0).rgb;
    c.c110 = texelFetch(tex, texelOf(ivec3(s.i1.x, s.i1.y, s.i0.z), grid), 0).rgb;
    c.c001 = texelFetch(tex, texelOf(ivec3(s.i0.x, s.i0.y, s.i1.z), grid), 0).rgb;
    c.c101 = texelFetch(tex, texelOf(ivec3(s.i1.x, s.i0.y, s.i1.z), grid), 0).rgb;
    c.c011 = texelFetch(tex, texelOf(ivec3(s.i0.x, s.i1.y, s.i1.z), grid), 0).rgb;
    c.c111 = texelFetch(tex, texelOf(ivec3(s.i1.x, s.i1.y, s.i1.z), grid), 0).rgb;
    return c;
}

vec3 interpolateCorners(Corners c, vec3 f) {
    vec3 c00 = mix(c.c000, c.c100, f.x), c10 = mix(c.c010, c.c110, f.x);
    vec3 c01 = mix(c.c001, c.c101, f.x), c11 = mix(c.c011, c.c111, f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

// Trilinear on a texture of its own lattice (light depth, lobes).
vec3 fetchTrilinear(sampler3D tex, Stencil s) {
#if VOLSTYLE_HW_FILTER
    // The texture unit's filter (clamp-to-edge sampler): fast, but GPUs quantise its weights.
    return texture(tex, (s.p + 0.5) / vec3(s.n)).rgb;
#else
    return interpolateCorners(fetchCorners(tex, s, false), s.f);
#endif
}

// Trilinear on a property grid (extinction, albedo, emission), dense or sparse.
vec3 sampleGrid(sampler3D grid, Stencil s) {
#if VOLSTYLE_HW_FILTER && !VOLSTYLE_SPARSE
    return texture(grid, (s.p + 0.5) / vec3(s.n)).rgb;
#else
    return interpolateCorners(fetchCorners(grid, s, true), s.f);
#endif
}

// The corners of the voxel cell last sampled: a march along a ray samples each cell about
// 1 / step times in a row, so its 8 fetches are shared by those samples (exactly the values
// fetchTrilinear reads). Used by light_depth.comp's rows.
struct CellCache {
    ivec3 i0;
    Corners corners;
};

CellCache emptyCellCache() {
    CellCache cache;
    cache.i0 = ivec3(-1);
    return cache;
}

vec3 extinctionAt(inout CellCache cache, vec3 p) {
    Stencil s = stencilAt(p);
    if (s.i0 != cache.i0) {
        cache.i0 = s.i0;
        cache.corners = fetchCorners(s_extinction, s, true);
    }
    return interpolateCorners(cache.corners, s.f);
}

// Ray (o + t d) against the voxels' box, in index space: [tEnter, tExit], empty if x > y.
vec2 intersectVolumeBox(vec3 o, vec3 d) {
    vec3 invD = 1.0 / mix(d, vec3(1e-30), equal(d, vec3(0.0)));
    vec3 t0 = (vec3(-0.5) - o) * invD;
    vec3 t1 = (vec3(u.dims.xyz) - 0.5 - o) * invD;
    vec3 lo = min(t0, t1), hi = max(t0, t1);
    return vec2(max(lo.x, max(lo.y, lo.z)), min(hi.x, min(hi.y, hi.z)));
}

// 1 - exp(-x) without cancellation for small optical depths (thin media, σt down to 1e-8).
vec3 oneMinusExp(vec3 x) {
    vec3 series = x * (1.0 - x * (0.5 - x * (1.0 / 6.0)));
    return mix(1.0 - exp(-x), series, lessThan(x, vec3(1e-3)));
}

// Ray segments shared by every march. A ray's span [t0, t0 + n·dt] inside the volume is cut into
// n = ceil(length_in_voxels / step) equal segments, each sampled at its midpoint, so a constant
// medium integrates exactly: Σ T_i (1 - e^{-σ dt}) = 1 - e^{-σ L} (TVCG Eq. 1, Listing 1).
#include "common/volume.glsl"

#ifndef VOLSTYLE_SKIP_EMPTY
#define VOLSTYLE_SKIP_EMPTY 1
#endif

struct Segments {
    float t0;
    float dt;
    int count;
};

Segments makeSegments(vec2 range, vec3 dIndex) {
    Segments s;
    float voxels = (range.y - range.x) * length(dIndex);
    s.count = max(1, int(ceil(voxels / u.march.x)));
    s.t0 = range.x;
    s.dt = (range.y - range.x) / float(s.count);
    return s;
}

float segmentMidpoint(Segments s, int i) { return s.t0 + (float(i) + 0.5) * s.dt; }

// Empty-space skipping: if the midpoint of segment i lies in a brick whose extinction (with a
// one-voxel apron, the reach of trilinear interpolation) is zero, return the first segment whose
// midpoint is past that brick; otherwise i. Skipped segments contribute exactly nothing, so
// skipping changes no result.
int skipEmptyBricks(int i, Segments s, vec3 o, vec3 d) {
#if VOLSTYLE_SKIP_EMPTY
    vec3 p = o + segmentMidpoint(s, i) * d;
    ivec3 brick = clamp(ivec3(floor((p + 0.5) / float(kBrickSize))), ivec3(0), u.brickDims.xyz - 1);
    if (texelFetch(s_occupancy, brick, 0).r > 0.0) return i;
    vec3 lo = vec3(brick * kBrickSize) - 0.5, hi = lo + float(kBrickSize);
    vec3 invD = 1.0 / mix(d, vec3(1e-30), equal(d, vec3(0.0)));
    vec3 tFar = max((lo - o) * invD, (hi - o) * invD);
    float tExit = min(tFar.x, min(tFar.y, tFar.z));
    return max(i + 1, int(ceil((tExit - s.t0) / s.dt - 0.5)));
#else
    return i;
#endif
}

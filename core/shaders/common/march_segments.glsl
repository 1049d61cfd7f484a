// The equal segments of a march and empty-space skipping over occupancy bricks, for any grid in
// index space (voxel (i,j,k) centred at (i,j,k); a brick is kBrickSize voxels a side, its
// occupancy the largest value a trilinear lookup inside it can read: the brick and a one-voxel
// apron, occupancy.comp). The renderer's march (common/march.glsl) and the stylizer's march
// through the session's volume (stylize.comp) share these, so both skip exactly the segments
// whose midpoints lie in empty bricks, and skipping changes no result.
#include "common/ray_box.glsl"

struct Segments {
    float t0;
    float dt;
    int count;
};

float segmentMidpoint(Segments s, int i) { return s.t0 + (float(i) + 0.5) * s.dt; }

// The occupancy brick holding index-space point p.
ivec3 brickAt(vec3 p, ivec3 brickDims) { return clamp(ivec3(floor((p + 0.5) / float(kBrickSize))), ivec3(0), brickDims - 1); }

// Where the ray o + t d leaves `brick`.
float brickExit(ivec3 brick, vec3 o, vec3 invD) {
    vec3 lo = vec3(brick * kBrickSize) - 0.5;
    return rayBox(o, invD, lo, lo + float(kBrickSize)).y;
}

// If the midpoint of segment i lies in an empty brick, the first segment whose midpoint is past
// that brick; otherwise i.
int skipEmptyBricksOn(sampler3D occupancy, ivec3 brickDims, int i, Segments s, vec3 o, vec3 d) {
    ivec3 brick = brickAt(o + segmentMidpoint(s, i) * d, brickDims);
    if (texelFetch(occupancy, brick, 0).r > 0.0) return i;
    return max(i + 1, int(ceil((brickExit(brick, o, safeInverse(d)) - s.t0) / s.dt - 0.5)));
}

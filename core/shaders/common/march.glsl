// Ray segments shared by every march. Marching (the default): a ray's span [t0, t0 + n·dt] inside
// the volume is cut into n = ceil(length_in_voxels / step) equal segments, each sampled at its
// midpoint, so a constant medium integrates exactly: Σ T_i (1 - e^{-σ dt}) = 1 - e^{-σ L} (TVCG
// Eq. 1, Listing 1). Exact traversal (VOLSTYLE_EXACT_TRAVERSAL, TVCG Sec. 5.2 after [44]): one
// segment per voxel cell the ray crosses, found by stepping from face to face (Amanatides–Woo),
// so the box basis's weights — the length inside each cell — are exact.
#include "common/volume.glsl"
#include "common/ray_box.glsl"

#ifndef VOLSTYLE_SKIP_EMPTY
#define VOLSTYLE_SKIP_EMPTY 1
#endif
#ifndef VOLSTYLE_EXACT_TRAVERSAL
#define VOLSTYLE_EXACT_TRAVERSAL 0
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
    vec3 lo = vec3(brick * kBrickSize) - 0.5;
    float tExit = rayBox(o, safeInverse(d), lo, lo + float(kBrickSize)).y;
    return max(i + 1, int(ceil((tExit - s.t0) / s.dt - 0.5)));
#else
    return i;
#endif
}

// Where the ray leaves the occupancy brick holding p, if that brick is empty; else -1.
float emptyBrickExit(vec3 p, vec3 o, vec3 invD) {
#if VOLSTYLE_SKIP_EMPTY
    ivec3 brick = clamp(ivec3(floor((p + 0.5) / float(kBrickSize))), ivec3(0), u.brickDims.xyz - 1);
    if (texelFetch(s_occupancy, brick, 0).r > 0.0) return -1.0;
    vec3 lo = vec3(brick * kBrickSize) - 0.5;
    return rayBox(o, invD, lo, lo + float(kBrickSize)).y;
#else
    return -1.0;
#endif
}

// A ray being marched: the kernels call nextSegment() until it returns false.
struct RayMarch {
    vec3 o, d, invD;
    Segments seg;  // marching: the equal segments
    int i;         // marching: the next segment
    float t;       // exact traversal: where the next segment starts
    float tEnd;
};

RayMarch beginMarch(vec2 range, vec3 o, vec3 d) {
    RayMarch m;
    m.o = o;
    m.d = d;
    m.invD = safeInverse(d);
    m.seg = makeSegments(range, d);
    m.i = 0;
    m.t = range.x;
    m.tEnd = range.y;
    return m;
}

// The next segment (midpoint tMid, length dt). With `skip`, segments in empty bricks are jumped
// over: they contribute exactly nothing. False once the ray has left the volume.
bool nextSegment(inout RayMarch m, bool skip, out float tMid, out float dt) {
#if !VOLSTYLE_EXACT_TRAVERSAL
    while (m.i < m.seg.count) {
        if (skip) {
            int next = skipEmptyBricks(m.i, m.seg, m.o, m.d);
            if (next != m.i) {
                m.i = next;
                continue;
            }
        }
        tMid = segmentMidpoint(m.seg, m.i);
        dt = m.seg.dt;
        ++m.i;
        return true;
    }
    return false;
#else
    const float nudge = 1e-4 / max(length(m.d), 1e-30);  // 1e-4 voxel: inside the next cell
    while (m.t < m.tEnd - nudge) {
        vec3 p = m.o + (m.t + nudge) * m.d;
        if (skip) {
            float exit = emptyBrickExit(p, m.o, m.invD);
            if (exit > m.t) {
                m.t = exit;
                continue;
            }
        }
        // Leave the cell [c - 0.5, c + 0.5] through the nearest face ahead.
        vec3 cell = floor(p + 0.5);
        vec3 face = cell + 0.5 * sign(m.d);
        vec3 tFace = mix((face - m.o) * m.invD, vec3(3e38), equal(m.d, vec3(0.0)));
        float tNext = min(min(tFace.x, min(tFace.y, tFace.z)), m.tEnd);
        tNext = max(tNext, m.t + nudge);
        tMid = 0.5 * (m.t + tNext);
        dt = tNext - m.t;
        m.t = tNext;
        return true;
    }
    return false;
#endif
}

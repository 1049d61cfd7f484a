// Ray segments shared by every march. Marching (the default): a ray's span [t0, t0 + n·dt] inside
// the volume is cut into n = ceil(length_in_voxels / step) equal segments, each sampled at its
// midpoint, so a constant medium integrates exactly: Σ T_i (1 - e^{-σ dt}) = 1 - e^{-σ L} (TVCG
// Eq. 1, Listing 1). Exact traversal (VOLSTYLE_EXACT_TRAVERSAL, TVCG Sec. 5.2 after [44]): one
// segment per voxel cell the ray crosses, found by stepping from face to face (Amanatides–Woo),
// so the box basis's weights — the length inside each cell — are exact.
// Curved rays (VOLSTYLE_CURVED, issue #16): a view ray bent by the refractive index is a polyline
// traced on the CPU (core/render/curved_paths.h); each of its straight pieces is marched as a
// straight ray is, so W and Wᵀ still share every segment. Without it the code below is the
// straight march, unchanged.
// Dense segments (splitDense, issue #34) are cut into sub-segments of bounded optical depth, by the
// occupancy bricks, so W and Wᵀ see the same cuts as the renderer.
#include "common/volume.glsl"
#include "common/march_segments.glsl"

#ifndef VOLSTYLE_SKIP_EMPTY
#define VOLSTYLE_SKIP_EMPTY 1
#endif
#ifndef VOLSTYLE_EXACT_TRAVERSAL
#define VOLSTYLE_EXACT_TRAVERSAL 0
#endif
#ifndef VOLSTYLE_CURVED
#define VOLSTYLE_CURVED 0
#endif

#if VOLSTYLE_CURVED
layout(std430, binding = kBindingPathStart) readonly buffer b_PathStart {
    uint pathStart[];  // pixel p's vertices: [pathStart[p], pathStart[p + 1])
};
layout(std430, binding = kBindingPathVertex) readonly buffer b_PathVertex {
    vec4 pathVertex[];  // xyz: index-space position; w: length along the path from the eye (world)
};
layout(std430, binding = kBindingPathExit) readonly buffer b_PathExit {
    vec4 pathExit[];  // per pixel: xyz the world direction its ray leaves in; w 0 when it misses
};
#endif

Segments makeSegments(vec2 range, vec3 dIndex) {
    Segments s;
    float voxels = (range.y - range.x) * length(dIndex);
    s.count = max(1, int(ceil(voxels / u.march.x)));
    s.t0 = range.x;
    s.dt = (range.y - range.x) / float(s.count);
    return s;
}

// Empty-space skipping over the volume's occupancy bricks (common/march_segments.glsl).
int skipEmptyBricks(int i, Segments s, vec3 o, vec3 d) {
#if VOLSTYLE_SKIP_EMPTY
    return skipEmptyBricksOn(s_occupancy, u.brickDims.xyz, i, s, o, d);
#else
    return i;
#endif
}

// Where the ray leaves the occupancy brick holding p, if that brick is empty; else -1.
float emptyBrickExit(vec3 p, vec3 o, vec3 invD) {
#if VOLSTYLE_SKIP_EMPTY
    ivec3 brick = brickAt(p, u.brickDims.xyz);
    if (texelFetch(s_occupancy, brick, 0).r > 0.0) return -1.0;
    return brickExit(brick, o, invD);
#else
    return -1.0;
#endif
}

// A ray being marched: the kernels call nextSegment() until it returns false.
struct RayMarch {
    vec3 o, d, invD;  // the straight ray (or the current piece of a curved one): o + t d
    Segments seg;  // marching: the equal segments
    int i;         // marching: the next segment
    float t;       // exact traversal: where the next segment starts
    float tEnd;
    bool fine;       // cut dense segments (splitDense); off where only ∫σ is marched
    int sub;         // the next sub-segment of a dense segment, of subCount
    int subCount;
    float subStart;  // where the dense segment starts, and its sub-segments' length
    float subDt;
#if VOLSTYLE_CURVED
    int vertex;      // the first vertex of the next piece
    int lastVertex;  // the path's last vertex
    vec2 range;      // [near, far] along the path
    vec3 w;          // the current piece's unit direction (world)
#endif
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
    m.fine = true;
    m.sub = m.subCount = 0;
    return m;
}

// Sub-segments of a segment whose occupancy brick allows optical depth `bound` (layout.h,
// kMarchDenseSegmentDepth: why). The tolerance keeps float rounding of a bound at a whole number
// of sub-segments from flipping the count (and the float64 oracle in step).
int denseSubsegments(float bound) { return clamp(int(ceil(bound / kMarchDenseSegmentDepth - 1e-3)), 1, kMarchMaxSubsegments); }

// Cuts the segment (tMid, dt) into equal sub-segments where the medium within a voxel of it is
// dense: tMid and dt become the first one's, and nextSegment returns the others before moving on.
void splitDense(inout RayMarch m, inout float tMid, inout float dt) {
    if (!m.fine) return;
    int k = denseSubsegments(texelFetch(s_occupancy, brickAt(m.o + tMid * m.d, u.brickDims.xyz), 0).r * dt);
    if (k <= 1) return;
    m.subStart = tMid - 0.5 * dt;
    m.subDt = dt / float(k);
    m.subCount = k;
    m.sub = 1;
    tMid = m.subStart + 0.5 * m.subDt;
    dt = m.subDt;
}

#if VOLSTYLE_CURVED
// The world direction of index-space displacement d.
vec3 worldDirection(vec3 d) { return normalize(inverse(mat3(u.indexFromWorld)) * d); }

// Moves to the path's next piece inside [near, far]; false at its end.
bool nextPiece(inout RayMarch m) {
    while (m.vertex < m.lastVertex) {
        vec4 a = pathVertex[m.vertex], b = pathVertex[m.vertex + 1];
        ++m.vertex;
        vec2 r = vec2(max(a.w, m.range.x), min(b.w, m.range.y));
        if (!(r.y > r.x) || !(b.w > a.w)) continue;
        vec3 d = (b.xyz - a.xyz) / (b.w - a.w);  // index units per unit of path length
        RayMarch piece = beginMarch(r, a.xyz - a.w * d, d);  // marched as a straight ray is
        piece.fine = m.fine;
        piece.vertex = m.vertex;
        piece.lastVertex = m.lastVertex;
        piece.range = m.range;
        piece.w = worldDirection(d);
        m = piece;
        return true;
    }
    return false;
}
#endif

// The next segment of the current straight ray or piece.
bool nextSegmentOnPiece(inout RayMarch m, bool skip, out float tMid, out float dt) {
    if (m.sub < m.subCount) {
        tMid = m.subStart + (float(m.sub) + 0.5) * m.subDt;
        dt = m.subDt;
        ++m.sub;
        return true;
    }
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
        splitDense(m, tMid, dt);
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
        splitDense(m, tMid, dt);
        return true;
    }
    return false;
#endif
}

// The next segment (midpoint tMid, length dt). With `skip`, segments in empty bricks are jumped
// over: they contribute exactly nothing. False once the ray has left the volume.
bool nextSegment(inout RayMarch m, bool skip, out float tMid, out float dt) {
#if VOLSTYLE_CURVED
    for (;;) {
        if (nextSegmentOnPiece(m, skip, tMid, dt)) return true;
        if (!nextPiece(m)) return false;
    }
#else
    return nextSegmentOnPiece(m, skip, tMid, dt);
#endif
}

// The ray's direction where the march is (world, unit): the view ray's, or the current piece's.
vec3 marchDirection(RayMarch m, vec3 viewDir) {
#if VOLSTYLE_CURVED
    return m.w;
#else
    return viewDir;
#endif
}

// The solver's linear operator W and its adjoint Wᵀ, from one source (TVCG Sec. 5.1, Listing 1):
// VOLSTYLE_ADJOINT = 0 renders the unknown field (W a, one value per pixel); = 1 scatters each
// pixel's residual back along the same ray with the same weights (Wᵀ r), so the two agree to
// float precision. Rays start, step, skip and end exactly as the renderer's do.
//
// VOLSTYLE_UNKNOWN: 1 emission (Eq. 6: weight T·(1 − e^{−σΔt})), 2 albedo (the same times L_scat,
// Sec. 4.2.2), 3 emission and albedo (two blocks of unknowns, Sec. 4.2.3), 4 extinction (log
// space, Sec. 4.2.4: weight Δt, the line integral of the basis).
// VOLSTYLE_BASIS: 0 box (nearest unknown voxel), 1 trilinear (hat functions at voxel centres).
// The unknown grid may be coarser than the extinction grid: both span the same box. Unknowns are
// vec4 per voxel (rgb used) so every solver vector shares one layout.
#include "common/march.glsl"
#include "common/lighting.glsl"
#include "common/camera.glsl"

// VOLSTYLE_UNKNOWN_* and VOLSTYLE_BASIS_* come from layout.h (core::Unknown, core::BasisType).

#ifndef VOLSTYLE_ADJOINT
#define VOLSTYLE_ADJOINT 0
#endif
#ifndef VOLSTYLE_BASIS
#define VOLSTYLE_BASIS VOLSTYLE_BASIS_TRILINEAR
#endif
#ifndef VOLSTYLE_HAS_FLOAT_ATOMICS
#define VOLSTYLE_HAS_FLOAT_ATOMICS 0
#endif
// VOLSTYLE_ROWS (core/solve/sparse_rows.h): instead of applying W or Wᵀ, write the rows of W
// themselves — the adjoint's accumulation with a residual of 1, each flushed corner one entry
// (element, weight) — and count or place their transpose. 1 counts, 2 fills.
#ifndef VOLSTYLE_ROWS
#define VOLSTYLE_ROWS 0
#endif
#ifndef VOLSTYLE_ROW_CHANNELS
#define VOLSTYLE_ROW_CHANNELS 3
#endif
// The adjoint and the row builder accumulate per corner; the forward gathers.
#define VOLSTYLE_ACCUMULATES (VOLSTYLE_ADJOINT || VOLSTYLE_ROWS)

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

#ifndef VOLSTYLE_ROW_MASK
#define VOLSTYLE_ROW_MASK 0
#endif
// The count pass counts each column's entries and the fill pass places each entry in its
// element's column too (atomics); 0: the rows alone, and the caller counts and transposes them (a
// CPU rasterizer, where these scattered atomics cost more than the march: core/solve/projector.cpp).
#ifndef VOLSTYLE_ROW_COLUMNS
#define VOLSTYLE_ROW_COLUMNS 1
#endif
#if VOLSTYLE_ROWS
#if VOLSTYLE_ROW_MASK
layout(std430, binding = kBindingRowMask) readonly buffer b_RowMask {
    vec4 pixelWeight[];  // the solver's √weights: a pixel with none gets an empty row
};
#endif
layout(std430, binding = kBindingRowStart) buffer b_RowStart {
    uint rowStart[];
};
layout(std430, binding = kBindingColStart) buffer b_ColStart {
    uint colStart[];
};
#if VOLSTYLE_ROWS == VOLSTYLE_ROWS_FILL
layout(std430, binding = kBindingRowIndex) writeonly buffer b_RowIndex {
    uint rowIndex[];
};
layout(std430, binding = kBindingRowWeight) writeonly buffer b_RowWeight {
    float rowWeight[];
};
#if VOLSTYLE_ROW_COLUMNS
layout(std430, binding = kBindingColCursor) buffer b_ColCursor {
    uint colCursor[];
};
layout(std430, binding = kBindingColIndex) writeonly buffer b_ColIndex {
    uint colIndex[];
};
layout(std430, binding = kBindingColWeight) writeonly buffer b_ColWeight {
    float colWeight[];
};
#endif
#endif
uint g_pixel = 0u;    // this invocation's pixel within its view
uint g_entries = 0u;  // entries of its row so far
#if VOLSTYLE_ROWS == VOLSTYLE_ROWS_FILL
// The slots the count pass reserved for this row, read once per ray: per entry, two loads of
// rowStart at a per-lane index were most of what writing the rows cost on llvmpipe (issue #40).
uint g_rowBegin = 0u, g_rowEnd = 0u;
#endif

// One entry of the row: counted (pass 1), or written to the row and to the element's column
// (pass 2, at the slot the count pass reserved).
void emitEntry(uint element, vec3 w) {
#if VOLSTYLE_ROWS == VOLSTYLE_ROWS_COUNT
#if VOLSTYLE_ROW_COLUMNS
    atomicAdd(colStart[element], 1u);
#endif
#else
    // The count pass reserved these slots; a ray that (by rounding in another compilation)
    // finds more entries than it counted drops the extra ones instead of writing a neighbour's.
    uint k = g_rowBegin + g_entries;
    if (k >= g_rowEnd) return;
#if VOLSTYLE_ROW_COLUMNS
    uint j = colStart[element] + atomicAdd(colCursor[element], 1u);
    if (j >= colStart[element + 1u]) return;
    colIndex[j] = g_pixel;
#if VOLSTYLE_ROW_CHANNELS == 1
    colWeight[j] = w.r;
#else
    colWeight[3u * j] = w.r, colWeight[3u * j + 1u] = w.g, colWeight[3u * j + 2u] = w.b;
#endif
#endif
    rowIndex[k] = element;
#if VOLSTYLE_ROW_CHANNELS == 1
    rowWeight[k] = w.r;
#else
    rowWeight[3u * k] = w.r, rowWeight[3u * k + 1u] = w.g, rowWeight[3u * k + 2u] = w.b;
#endif
#endif
    ++g_entries;
}
#elif VOLSTYLE_ADJOINT
#if VOLSTYLE_HAS_FLOAT_ATOMICS
layout(std430, binding = kBindingUnknown) buffer b_Unknown {
    float unknown[];
};
void scatterAdd(uint i, float v) { atomicAdd(unknown[i], v); }
#else
// No float atomics (core GL 4.5 has none): a compare-and-swap loop on the bits. Exact: every
// addition lands once.
layout(std430, binding = kBindingUnknown) buffer b_Unknown {
    uint unknownBits[];
};
void scatterAdd(uint i, float v) {
    uint seen = unknownBits[i];
    for (;;) {
        uint expected = seen;
        seen = atomicCompSwap(unknownBits[i], expected, floatBitsToUint(uintBitsToFloat(expected) + v));
        if (seen == expected) break;
    }
}
#endif
layout(std430, binding = kBindingResidual) readonly buffer b_Residual {
    vec4 residual[];
};
#else
// Forward reads whole elements: one vec4 load per basis function instead of three floats.
layout(std430, binding = kBindingUnknown) readonly buffer b_Unknown {
    vec4 unknown[];
};
layout(std430, binding = kBindingImageOut) writeonly buffer b_Image {
    vec4 pixels[];
};
#endif

#if VOLSTYLE_SPARSE
// A sparse unknown grid's table from brick to slot (core/volume/brick_layout.h).
layout(std430, binding = kBindingUnknownSlots) readonly buffer b_UnknownSlots {
    uint unknownSlotOfBrick[];
};
#endif

// The basis functions that are non-zero at extinction-index point p, over the unknown grid:
// the corners i0..i1 and fractions f of a trilinear stencil (box: one corner, weight 1). No arrays:
// llvmpipe keeps arrays in memory, which made the projector three times slower.
struct Basis {
    ivec3 i0;
    ivec3 i1;
    vec3 f;
};

Basis basisAt(vec3 p) {
    Basis b;
    ivec3 n = u.unknownDims.xyz;
    vec3 q = (p + 0.5) * u.unknownScale.xyz - 0.5;  // unknown-grid index space, same box
#if VOLSTYLE_BASIS == VOLSTYLE_BASIS_BOX
    b.i0 = b.i1 = clamp(ivec3(floor(q + 0.5)), ivec3(0), n - 1);
    b.f = vec3(0.0);
#else
    q = clamp(q, vec3(0.0), vec3(n - 1));
    b.i0 = min(ivec3(floor(q)), n - 1);
    b.i1 = min(b.i0 + 1, n - 1);
    b.f = q - vec3(b.i0);
#endif
    return b;
}

// Corner c of the stencil: its unknown index (within a block) and weight.
uint cornerIndex(Basis b, int c, out float weight) {
    bvec3 upper = bvec3((c & 1) != 0, (c & 2) != 0, (c & 4) != 0);
    ivec3 corner = mix(b.i0, b.i1, upper);
    vec3 w = mix(1.0 - b.f, b.f, upper);
    weight = w.x * w.y * w.z;
#if VOLSTYLE_SPARSE
    // A sparse volume's unknowns are the stored voxels of a sparse grid (the volume's own bricks,
    // or coarser ones): slot · 8³ + the voxel's place in its brick. A corner in an inactive brick
    // is the background brick's (outside the hull: never moved).
    ivec3 q = corner + u.unknownLayout.yzw;
    ivec3 bricks = (u.unknownDims.xyz + u.unknownLayout.yzw + kBrickSize - 1) / kBrickSize;
    ivec3 brick = q / kBrickSize, l = q % kBrickSize;
    int slot = int(unknownSlotOfBrick[(brick.z * bricks.y + brick.y) * bricks.x + brick.x]);
    return uint(slot * (kBrickSize * kBrickSize * kBrickSize) + (l.z * kBrickSize + l.y) * kBrickSize + l.x);
#else
    return uint((corner.z * u.unknownDims.y + corner.y) * u.unknownDims.x + corner.x);
#endif
}

// Consecutive samples of a ray mostly fall between the same 8 unknowns (at 0.5 voxels a step,
// about two per cell): W keeps the 8 values it loaded and Wᵀ sums into 8 registers, and either
// touches memory only when the stencil moves, for the same sums in the same order per corner.
// Named fields, not an array: llvmpipe keeps arrays in memory. One per block of unknowns.
struct CornerCache {
    Basis b;     // the stencil held (b.i0.x < 0: none)
    uint block;  // which block of unknowns (emission or albedo of a joint solve)
    vec3 v0, v1, v2, v3, v4, v5, v6, v7;
};

CornerCache emptyCache(uint block) {
    CornerCache c;
    c.b.i0 = c.b.i1 = ivec3(-1);
    c.b.f = vec3(0.0);
    c.block = block;
    c.v0 = c.v1 = c.v2 = c.v3 = c.v4 = c.v5 = c.v6 = c.v7 = vec3(0.0);
    return c;
}

#define VS_FOR_EACH_CORNER(X) X(0, v0) X(1, v1) X(2, v2) X(3, v3) X(4, v4) X(5, v5) X(6, v6) X(7, v7)

// W: add weight · (Σ basis · a) of the cache's block; Wᵀ: scatter weight · r · basis into it.
#if VOLSTYLE_ACCUMULATES
// A corner's sum leaves the cache: scattered into the unknowns (Wᵀ) or emitted as a row entry.
void flushCorner(CornerCache c, int corner, vec3 v) {
    if (v == vec3(0.0)) return;  // a weight-0 corner (or nothing summed) adds nothing
    float unusedWeight;
    uint element = c.block + cornerIndex(c.b, corner, unusedWeight);
#if VOLSTYLE_ROWS
    emitEntry(element, v);
#else
    scatterAdd(4u * element, v.r);
    scatterAdd(4u * element + 1u, v.g);
    scatterAdd(4u * element + 2u, v.b);
#endif
}
void flush(CornerCache c) {
    if (c.b.i0.x < 0) return;
#define VS_FLUSH(k, field) flushCorner(c, k, c.field);
    VS_FOR_EACH_CORNER(VS_FLUSH)
#undef VS_FLUSH
}
// Moving the stencil one cell along an axis: a ray's direction is fixed, so a voxel it has left
// behind is never in its stencil again. The corners left behind are flushed; the four shared
// ones move to their new slots. Each voxel is then flushed about once per ray (4 entries per
// cell crossed instead of 8). Corners k and k + step differ in that axis (step 1, 2, 4 for x, y, z).
void moveAlong(inout CornerCache c, int axis, int dir) {
    ivec3 n = u.unknownDims.xyz;
    if (axis == 0) {
        if (dir > 0) {
            flushCorner(c, 0, c.v0), flushCorner(c, 2, c.v2), flushCorner(c, 4, c.v4), flushCorner(c, 6, c.v6);
            c.v0 = c.v1, c.v2 = c.v3, c.v4 = c.v5, c.v6 = c.v7;
            c.v1 = c.v3 = c.v5 = c.v7 = vec3(0.0);
        } else {
            flushCorner(c, 1, c.v1), flushCorner(c, 3, c.v3), flushCorner(c, 5, c.v5), flushCorner(c, 7, c.v7);
            c.v1 = c.v0, c.v3 = c.v2, c.v5 = c.v4, c.v7 = c.v6;
            c.v0 = c.v2 = c.v4 = c.v6 = vec3(0.0);
        }
        c.b.i0.x += dir;
    } else if (axis == 1) {
        if (dir > 0) {
            flushCorner(c, 0, c.v0), flushCorner(c, 1, c.v1), flushCorner(c, 4, c.v4), flushCorner(c, 5, c.v5);
            c.v0 = c.v2, c.v1 = c.v3, c.v4 = c.v6, c.v5 = c.v7;
            c.v2 = c.v3 = c.v6 = c.v7 = vec3(0.0);
        } else {
            flushCorner(c, 2, c.v2), flushCorner(c, 3, c.v3), flushCorner(c, 6, c.v6), flushCorner(c, 7, c.v7);
            c.v2 = c.v0, c.v3 = c.v1, c.v6 = c.v4, c.v7 = c.v5;
            c.v0 = c.v1 = c.v4 = c.v5 = vec3(0.0);
        }
        c.b.i0.y += dir;
    } else {
        if (dir > 0) {
            flushCorner(c, 0, c.v0), flushCorner(c, 1, c.v1), flushCorner(c, 2, c.v2), flushCorner(c, 3, c.v3);
            c.v0 = c.v4, c.v1 = c.v5, c.v2 = c.v6, c.v3 = c.v7;
            c.v4 = c.v5 = c.v6 = c.v7 = vec3(0.0);
        } else {
            flushCorner(c, 4, c.v4), flushCorner(c, 5, c.v5), flushCorner(c, 6, c.v6), flushCorner(c, 7, c.v7);
            c.v4 = c.v0, c.v5 = c.v1, c.v6 = c.v2, c.v7 = c.v3;
            c.v0 = c.v1 = c.v2 = c.v3 = vec3(0.0);
        }
        c.b.i0.z += dir;
    }
    c.b.i1 = min(c.b.i0 + 1, n - 1);
}
void apply(Basis b, inout CornerCache cache, vec3 weight, vec3 r, inout vec3 unused) {
    vec3 v = weight * r;
#if VOLSTYLE_BASIS == VOLSTYLE_BASIS_BOX
    if (b.i0 != cache.b.i0) {  // the box's one corner, summed while the ray stays in its cell
        flush(cache);
        cache = emptyCache(cache.block);
        cache.b = b;
    }
    cache.v0 += v;
#else
    ivec3 delta = b.i0 - cache.b.i0;
    if (delta != ivec3(0)) {
        if (cache.b.i0.x >= 0 && all(lessThanEqual(abs(delta), ivec3(1)))) {
            if (delta.x != 0) moveAlong(cache, 0, delta.x);
            if (delta.y != 0) moveAlong(cache, 1, delta.y);
            if (delta.z != 0) moveAlong(cache, 2, delta.z);
        } else {  // a jump (empty space skipped) or the first sample
            flush(cache);
            cache = emptyCache(cache.block);
        }
        cache.b = b;
    }
    float w;
#define VS_SUM(k, field) cornerIndex(b, k, w); cache.field += v * w;
    VS_FOR_EACH_CORNER(VS_SUM)
#undef VS_SUM
#endif
}
#else
void flush(CornerCache unused) {}
void apply(Basis b, inout CornerCache cache, vec3 weight, vec3 unusedResidual, inout vec3 sum) {
    float w;
#if VOLSTYLE_BASIS == VOLSTYLE_BASIS_BOX
    sum += weight * unknown[cache.block + cornerIndex(b, 0, w)].rgb;  // w = 1: the box's one corner
#else
    if (b.i0 != cache.b.i0) {
        cache.b = b;
#define VS_LOAD(k, field) cache.field = unknown[cache.block + cornerIndex(b, k, w)].rgb;
        VS_FOR_EACH_CORNER(VS_LOAD)
#undef VS_LOAD
    }
    vec3 a = vec3(0.0);
#define VS_GATHER(k, field) cornerIndex(b, k, w); a += w * cache.field;
    VS_FOR_EACH_CORNER(VS_GATHER)
#undef VS_GATHER
    sum += weight * a;
#endif
}
#endif

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy) + u.dispatchOffset.xy;  // chunked_dispatch.h (work ahead's rows)
    if (pix.x >= u.imageSize.x || pix.y >= u.imageSize.y) return;
    uint pixelIndex = uint(u.viewPixels.x + pix.y * u.imageSize.x + pix.x);
#if VOLSTYLE_ROWS
    g_pixel = uint(pix.y * u.imageSize.x + pix.x);
    g_entries = 0u;
    vec3 r = vec3(1.0);  // the weights themselves
#if VOLSTYLE_ROWS == VOLSTYLE_ROWS_FILL
    g_rowBegin = rowStart[g_pixel];
    g_rowEnd = rowStart[g_pixel + 1u];
    if (g_rowEnd == g_rowBegin) return;  // an empty row (a pixel without weight, or a ray that misses)
#endif
#if VOLSTYLE_ROW_MASK
    if (pixelWeight[pixelIndex].rgb == vec3(0.0)) {
#if VOLSTYLE_ROWS == VOLSTYLE_ROWS_COUNT
        rowStart[g_pixel] = 0u;
#endif
        return;
    }
#endif
#elif VOLSTYLE_ADJOINT
    vec3 r = residual[pixelIndex].rgb;
    if (r == vec3(0.0)) return;  // weight-0 pixels scatter nothing
#else
    vec3 r = vec3(0.0);
#endif
    vec3 sum = vec3(0.0);

    vec3 dir = cameraRay(pix);
    RayMarch m;
    if (beginViewMarch(pix, dir, m)) {
        float tMid, dt;
#if VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EXTINCTION
        // Log-space tomography: o_k = Σ σ_i ∫ v_i dt. The current extinction is not involved,
        // so no skipping: every segment of the box counts.
        CornerCache cache = emptyCache(0u);
        m.fine = false;  // ∫ v_i dt needs no cuts, and must not follow the current extinction
        while (nextSegment(m, false, tMid, dt)) apply(basisAt(m.o + tMid * m.d), cache, vec3(dt), r, sum);
        flush(cache);
#else
        vec3 transmittance = vec3(1.0);
        uint albedoBlock = VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION_ALBEDO ? uint(u.unknownLayout.x) : 0u;
        CornerCache emission = emptyCache(0u), albedo = emptyCache(albedoBlock);
        while (nextSegment(m, true, tMid, dt)) {
            vec3 p = m.o + tMid * m.d;
            vec3 sigma = sampleGrid(s_extinction, stencilAt(p));
            if (max3(sigma) <= 0.0) continue;
            vec3 tau = sigma * dt;
            vec3 opacity = transmittance * oneMinusExp(tau);  // T · (1 − e^{−σΔt})
            Basis b = basisAt(p);
#if VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION || VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION_ALBEDO
            apply(b, emission, opacity, r, sum);
#endif
#if (VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_ALBEDO || VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION_ALBEDO) && \
    VOLSTYLE_ROWS == VOLSTYLE_ROWS_COUNT && VOLSTYLE_LIT
            // Counting needs only an upper bound on the entries the fill finds, and the fill emits
            // a corner only where some sample's basis weight is not 0: every corner a sample with
            // extinction reaches is counted, weight 1, and the light marches are skipped (issue
            // #40: they were most of the count pass of an albedo solve). No rounding of T, opacity
            // or L_scat can make the fill find more; where they make it find fewer, the row's last
            // slots stay element 0 with weight 0.
            apply(b, albedo, vec3(1.0), r, sum);
#elif VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_ALBEDO || VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION_ALBEDO
            apply(b, albedo, opacity * inScattering(p, marchDirection(m, dir)), r, sum);
#endif
            transmittance *= exp(-tau);
            // Only a transmittance cut-off: forward and adjoint must stop at the same segment.
            if (max3(transmittance) < u.projectorCutoff.x) break;
        }
        flush(emission);
        flush(albedo);
#endif
    }
#if VOLSTYLE_ROWS == VOLSTYLE_ROWS_COUNT
    rowStart[g_pixel] = g_entries;
#elif !VOLSTYLE_ADJOINT && !VOLSTYLE_ROWS
    pixels[pixelIndex] = vec4(sum, 0.0);
#endif
}

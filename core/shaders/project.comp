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

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

#if VOLSTYLE_ADJOINT
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

// The basis functions that are non-zero at extinction-index point p, over the unknown grid:
// the corners i0..i1 and fractions f of a trilinear stencil (box: one corner, weight 1). No arrays:
// llvmpipe keeps arrays in memory, which made the projector three times slower.
struct Basis {
    ivec3 i0;
    ivec3 i1;
    vec3 f;
};
#if VOLSTYLE_BASIS == VOLSTYLE_BASIS_BOX
const int kBasisCount = 1;
#else
const int kBasisCount = 8;
#endif

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
    return uint((corner.z * u.unknownDims.y + corner.y) * u.unknownDims.x + corner.x);
}

// W: add weight · (Σ basis · a) of block `block`; Wᵀ: scatter weight · r · basis into it.
#if VOLSTYLE_ADJOINT
void apply(Basis b, uint block, vec3 weight, vec3 r, inout vec3 unused) {
    vec3 v = weight * r;
    for (int c = 0; c < kBasisCount; ++c) {
        float w;
        uint i = 4u * (block + cornerIndex(b, c, w));
        if (w == 0.0) continue;
        scatterAdd(i, v.r * w);
        scatterAdd(i + 1u, v.g * w);
        scatterAdd(i + 2u, v.b * w);
    }
}
#else
void apply(Basis b, uint block, vec3 weight, vec3 unusedResidual, inout vec3 sum) {
    vec3 a = vec3(0.0);
    for (int c = 0; c < kBasisCount; ++c) {
        float w;
        uint i = block + cornerIndex(b, c, w);
        a += w * unknown[i].rgb;
    }
    sum += weight * a;
}
#endif

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    if (pix.x >= u.imageSize.x || pix.y >= u.imageSize.y) return;
    uint pixelIndex = uint(u.viewPixels.x + pix.y * u.imageSize.x + pix.x);
#if VOLSTYLE_ADJOINT
    vec3 r = residual[pixelIndex].rgb;
    if (r == vec3(0.0)) return;  // weight-0 pixels scatter nothing
#else
    vec3 r = vec3(0.0);
#endif
    vec3 sum = vec3(0.0);

    vec3 dir = cameraRay(pix);
    vec3 o, d;
    vec2 range;
    viewRay(dir, o, d, range);
    if (range.x < range.y) {
        RayMarch m = beginMarch(range, o, d);
        float tMid, dt;
#if VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EXTINCTION
        // Log-space tomography: o_k = Σ σ_i ∫ v_i dt. The current extinction is not involved,
        // so no skipping: every segment of the box counts.
        while (nextSegment(m, false, tMid, dt)) apply(basisAt(o + tMid * d), 0u, vec3(dt), r, sum);
#else
        vec3 transmittance = vec3(1.0);
        while (nextSegment(m, true, tMid, dt)) {
            vec3 p = o + tMid * d;
            vec3 sigma = fetchTrilinear(s_extinction, stencilAt(p));
            if (max3(sigma) <= 0.0) continue;
            vec3 tau = sigma * dt;
            vec3 opacity = transmittance * oneMinusExp(tau);  // T · (1 − e^{−σΔt})
            Basis b = basisAt(p);
#if VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION || VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION_ALBEDO
            apply(b, 0u, opacity, r, sum);
#endif
#if VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_ALBEDO || VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION_ALBEDO
            uint albedoBlock = VOLSTYLE_UNKNOWN == VOLSTYLE_UNKNOWN_EMISSION_ALBEDO ? uint(u.unknownLayout.x) : 0u;
            apply(b, albedoBlock, opacity * inScattering(p, dir), r, sum);
#endif
            transmittance *= exp(-tau);
            // Only a transmittance cut-off: forward and adjoint must stop at the same segment.
            if (max3(transmittance) < u.projectorCutoff.x) break;
        }
#endif
    }
#if !VOLSTYLE_ADJOINT
    pixels[pixelIndex] = vec4(sum, 0.0);
#endif
}

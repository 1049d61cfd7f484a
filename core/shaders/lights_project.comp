// The lights unknown's operator T and its adjoint Tᵀ (SPEC §8; TVCG Sec. 4.4, 5.3), from one
// source: the volume is fixed and the unknowns are the radiances c_i of the environment's lobes,
// so a pixel's value is o = Σ_i c_i ∫ T(0,t) σt ρ p(ω_i·(−ω)) Ω_i T_i(x_t) dt, with T_i the
// lobe's light volume (common/lobes.glsl).
//   VOLSTYLE_ADJOINT = 0: T c — every lobe gathered along each view ray in one pass (the
//     coefficients are LobeParams.radiance), one value per pixel;
//   VOLSTYLE_ADJOINT = 1: Tᵀ r for the kLobeChunk lobes from u.lobeKernel.x — each ray sums its
//     residual times the same weights per lobe, the workgroup adds its rays' sums by a tree
//     reduction in shared memory, and one invocation writes the group's sums: no atomics (the
//     paper's mipmap gather); the host adds the groups' sums in double.
// With VOLSTYLE_BACKGROUND_LOBES the lobes are also the background: each ray adds T(0,s) to the
// column of the lobe whose cell its direction falls in.
// Rays start, step, skip and stop exactly as project.comp's (its transmittance cut-off), so
// ⟨T c, r⟩ = ⟨c, Tᵀ r⟩ to float precision.
#include "common/march.glsl"
#include "common/lighting.glsl"
#include "common/camera.glsl"

#ifndef VOLSTYLE_ADJOINT
#define VOLSTYLE_ADJOINT 0
#endif
#ifndef VOLSTYLE_HAS_ALBEDO
#define VOLSTYLE_HAS_ALBEDO 0
#endif
#if !VOLSTYLE_HAS_LOBES
#error lights_project.comp needs the lobes (VOLSTYLE_HAS_LOBES)
#endif

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

#if VOLSTYLE_HAS_ALBEDO
layout(binding = kUnitAlbedo) uniform sampler3D s_albedo;
#endif

#if VOLSTYLE_ADJOINT
layout(std430, binding = kBindingResidual) readonly buffer b_Residual {
    vec4 residual[];
};
layout(std430, binding = kBindingLobeSums) writeonly buffer b_LobeSums {
    vec4 lobeSums[];  // (this view's first group u.lobeKernel.z + group) * kLobeChunk + lobe
};
const uint kGroupSize = uint(kWorkgroup2D * kWorkgroup2D);
shared vec3 s_sums[kWorkgroup2D * kWorkgroup2D * kLobeChunk];  // [invocation][lobe of the chunk]
#else
layout(std430, binding = kBindingImageOut) writeonly buffer b_Image {
    vec4 pixels[];
};
#endif

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    bool inside = pix.x < u.imageSize.x && pix.y < u.imageSize.y;
    uint pixelIndex = uint(u.viewPixels.x + pix.y * u.imageSize.x + pix.x);
#if VOLSTYLE_ADJOINT
    uint local = gl_LocalInvocationIndex;
    int first = u.lobeKernel.x, count = u.lobeKernel.y;
    for (int k = 0; k < kLobeChunk; ++k) s_sums[local * uint(kLobeChunk) + uint(k)] = vec3(0.0);
    vec3 r = inside ? residual[pixelIndex].rgb : vec3(0.0);
    bool marched = r != vec3(0.0);  // weight-0 pixels (and those outside the image) add nothing
#else
    bool marched = inside;
    vec3 sum = vec3(0.0);
#endif
    if (marched) {
        vec3 dir = cameraRay(pix);
        vec3 transmittance = vec3(1.0);
        RayMarch m;
        if (beginViewMarch(pix, dir, m)) {
            float tMid, dt;
            while (nextSegment(m, true, tMid, dt)) {
                vec3 p = m.o + tMid * m.d;
                Stencil st = stencilAt(p);
                vec3 sigma = sampleGrid(s_extinction, st);
                if (max3(sigma) <= 0.0) continue;
                vec3 tau = sigma * dt;
                vec3 w = transmittance * oneMinusExp(tau);  // T · (1 − e^{−σΔt}), then ρ
#if VOLSTYLE_HAS_ALBEDO
                w *= sampleGrid(s_albedo, st);
#endif
#if VOLSTYLE_ADJOINT
                LobeStencil ls = lobeStencilAt(p);
                vec3 rw = r * w;
                vec3 along = marchDirection(m, dir);
                for (int k = 0; k < count; ++k) s_sums[local * uint(kLobeChunk) + uint(k)] += rw * lobeResponse(ls, first + k, along);
#else
                sum += w * lobeInScattering(p, marchDirection(m, dir));
#endif
                transmittance *= exp(-tau);
                if (max3(transmittance) < u.projectorCutoff.x) break;  // as project.comp
            }
        }
#if VOLSTYLE_BACKGROUND_LOBES
        // The lobes seen directly (Background::fromLobes): the cell the ray leaves through adds
        // its radiance times T(0, s), the transmittance left at the ray's end.
        int cell = lobeCellOf(exitDirection(pix, dir));
        if (cell >= 0) {
#if VOLSTYLE_ADJOINT
            int k = cell - first;
            if (k >= 0 && k < count) s_sums[local * uint(kLobeChunk) + uint(k)] += r * transmittance;
#else
            sum += transmittance * lobes.radiance[cell].rgb;
#endif
        }
#endif
    }
#if VOLSTYLE_ADJOINT
    // Tree reduction over the group's invocations (every invocation reaches every barrier).
    for (uint stride = kGroupSize / 2u; stride > 0u; stride >>= 1u) {
        barrier();
        if (local < stride)
            for (int k = 0; k < kLobeChunk; ++k)
                s_sums[local * uint(kLobeChunk) + uint(k)] += s_sums[(local + stride) * uint(kLobeChunk) + uint(k)];
    }
    if (local == 0u) {
        uint group = uint(u.lobeKernel.z) + gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
        for (int k = 0; k < kLobeChunk; ++k) lobeSums[group * uint(kLobeChunk) + uint(k)] = vec4(s_sums[uint(k)], 0.0);
    }
#else
    if (inside) pixels[pixelIndex] = vec4(sum, 0.0);
#endif
}

// Single-scattering rendering (SPEC §1; TVCG Eq. 1-2): one invocation per pixel marches its ray
// through the volume, accumulating emission and sun in-scattering attenuated by transmittance,
// then adds the attenuated background.
//
// Variant defines: VOLSTYLE_HAS_EMISSION, VOLSTYLE_HAS_ALBEDO (else albedo 1),
// VOLSTYLE_NUM_LIGHTS (0..kLightSlots), VOLSTYLE_HAS_LOBES (the environment lights the medium;
// with no lights either, in-scattering is compiled out), VOLSTYLE_HAS_ENVIRONMENT (with
// VOLSTYLE_BACKGROUND_PLATE: it is the view's plate),
// VOLSTYLE_SKIP_EMPTY, VOLSTYLE_HW_FILTER, VOLSTYLE_EXACT_TRAVERSAL, VOLSTYLE_LAYERS (also write
// the compositing layers: the medium's light alone, premultiplied, and its emitted and scattered
// parts, the transmittance and the background, planar in b_Layers), VOLSTYLE_ALBEDO_ONE_LAYER (with
// LAYERS: a sixth, the scattering the same march gives at albedo 1 — the reach analysis asks what
// an albedo solve could reach without a second render of a white volume).
#include "common/march.glsl"
#include "common/lighting.glsl"
#include "common/camera.glsl"

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

layout(std430, binding = kBindingImageOut) writeonly buffer b_Image {
    vec4 pixels[];
};

#if VOLSTYLE_LAYERS
layout(std430, binding = kBindingLayersOut) writeonly buffer b_Layers {
    vec4 layers[];  // layer k of pixel p at k * pixelCount + p
};
#endif

#if VOLSTYLE_HAS_EMISSION
layout(binding = kUnitEmission) uniform sampler3D s_emission;
#endif
#if VOLSTYLE_HAS_ALBEDO
layout(binding = kUnitAlbedo) uniform sampler3D s_albedo;
#endif

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy) + u.dispatchOffset.xy;  // chunked_dispatch.h
    if (pix.x >= u.imageSize.x || pix.y >= u.imageSize.y) return;

    // The view ray in index space, parameterised by world distance t (or its refracted path).
    vec3 dir = cameraRay(pix);
    vec3 radiance = vec3(0.0);
    vec3 transmittance = vec3(1.0);
    vec3 emitted = vec3(0.0), scattered = vec3(0.0);  // the parts of radiance (VOLSTYLE_LAYERS)
    vec3 scatteredAtAlbedoOne = vec3(0.0);             // VOLSTYLE_ALBEDO_ONE_LAYER
    RayMarch m;
    if (beginViewMarch(pix, dir, m)) {
        float tMid, dt;
        while (nextSegment(m, true, tMid, dt)) {
            Stencil st = stencilAt(m.o + tMid * m.d);
            vec3 sigma = sampleGrid(s_extinction, st);
            if (max3(sigma) <= 0.0) continue;

            // Medium radiance L_m = L_e + ρ L_scat at the segment midpoint (Eq. 2).
            vec3 Le = vec3(0.0), Ls = vec3(0.0);
#if VOLSTYLE_HAS_EMISSION
            Le = sampleGrid(s_emission, st);
#endif
#if VOLSTYLE_LIT
#if VOLSTYLE_HAS_ALBEDO
            vec3 albedo = sampleGrid(s_albedo, st);
#else
            vec3 albedo = vec3(1.0);
#endif
            vec3 Lin = inScattering(st.p, marchDirection(m, dir));
            Ls = albedo * Lin;
#endif
            // Segment of optical depth τ = σ dt: opacity 1 - e^{-τ}, then attenuate.
            vec3 tau = sigma * dt;
            vec3 w = transmittance * oneMinusExp(tau);
            radiance += w * (Le + Ls);
#if VOLSTYLE_LAYERS
            emitted += w * Le;
            scattered += w * Ls;
#if VOLSTYLE_ALBEDO_ONE_LAYER && VOLSTYLE_LIT
            scatteredAtAlbedoOne += w * Lin;
#endif
#endif
            transmittance *= exp(-tau);
            // Early ray termination: what is left to gather is at most T·L_max (march.z).
            float T = max3(transmittance);
            if ((T < u.march.y && T * u.march.z <= u.march.y * max3(radiance)) || T < 1e-3 * u.march.y) break;
        }
    }
    vec3 background = backgroundRadiance(pix, exitDirection(pix, dir));
    // Summed as 1 − T per channel: a ray that meets no medium gets alpha 0 exactly. 1 − ΣT/3 did
    // not on NVIDIA (−1.2e-7: its division is by an approximate reciprocal, which GLSL allows).
    float alpha = clamp(dot(vec3(1.0) - transmittance, vec3(1.0)) / 3.0, 0.0, 1.0);
    int p = pix.y * u.imageSize.x + pix.x;
    pixels[p] = vec4(radiance + transmittance * background, alpha);
#if VOLSTYLE_LAYERS
    int n = u.imageSize.x * u.imageSize.y;
    layers[p] = vec4(radiance, alpha);  // premultiplied: over a plate B gives radiance + (1 - alpha) B
    layers[n + p] = vec4(emitted, alpha);
    layers[2 * n + p] = vec4(scattered, alpha);
    layers[3 * n + p] = vec4(transmittance, 1.0);
    layers[4 * n + p] = vec4(background, 1.0);
#if VOLSTYLE_ALBEDO_ONE_LAYER
    layers[5 * n + p] = vec4(scatteredAtAlbedoOne, alpha);
#endif
#endif
}

// Sun in-scattering, phase functions and the background (SPEC §1).
#include "common/volume.glsl"

#ifndef VOLSTYLE_NUM_LIGHTS
#define VOLSTYLE_NUM_LIGHTS 0
#endif
#ifndef VOLSTYLE_HAS_ENVIRONMENT
#define VOLSTYLE_HAS_ENVIRONMENT 0
#endif

const float kInvFourPi = 0.07957747154594767;

// p(cos) with cos = ω_l·(−ω); Henyey–Greenstein in pbrt's convention (g > 0: forward).
float phaseFunction(float cosTheta) {
    if (u.phase.x < 0.5) return kInvFourPi;
    float g = u.phase.y;
    float denom = 1.0 + g * g + 2.0 * g * cosTheta;
    return kInvFourPi * (1.0 - g * g) / (denom * sqrt(max(denom, 1e-12)));
}

#if VOLSTYLE_NUM_LIGHTS > 0
// Optical depth toward each light, stored per voxel centre by light_depth.comp. Interpolating the
// depth (not the transmittance) is exact for slabs, where the depth is linear.
layout(binding = kUnitLightDepth0) uniform sampler3D s_lightDepth[kLightSlots];

// L_scat(x, ω) = Σ_l p(ω_l·(−ω)) E_l T_l(x)   (V_l = 1: no occluders)
vec3 inScattering(Stencil st, vec3 dir) {
    vec3 sum = vec3(0.0);
    for (int l = 0; l < VOLSTYLE_NUM_LIGHTS; ++l) {
        vec3 depth = fetchTrilinear(s_lightDepth[l], st);
        sum += phaseFunction(dot(u.lightDirection[l].xyz, -dir)) * u.lightIrradiance[l].rgb * exp(-depth);
    }
    return sum;
}
#endif

#if VOLSTYLE_HAS_ENVIRONMENT
layout(binding = kUnitEnvironment) uniform sampler2D s_environment;
#endif

// Background radiance seen along ω: the lat-long map (u = 0.5 + atan2(x, -z)/2π, v = acos(y)/π)
// or the constant colour.
vec3 backgroundRadiance(vec3 dir) {
#if VOLSTYLE_HAS_ENVIRONMENT
    vec2 uv = vec2(0.5 + atan(dir.x, -dir.z) * 0.15915494309189535, acos(clamp(dir.y, -1.0, 1.0)) * 0.3183098861837907);
    return texture(s_environment, uv).rgb;
#else
    return u.background.rgb;
#endif
}

// In-scattering from the lights and the environment's lobes, phase functions and the background
// (SPEC §1, §8).
#include "common/volume.glsl"
#include "common/precise_math.glsl"
#include "common/phase.glsl"

#ifndef VOLSTYLE_NUM_LIGHTS
#define VOLSTYLE_NUM_LIGHTS 0
#endif
#ifndef VOLSTYLE_HAS_ENVIRONMENT
#define VOLSTYLE_HAS_ENVIRONMENT 0
#endif
#ifndef VOLSTYLE_BACKGROUND_PLATE  // s_environment holds a per-view plate, pixel-aligned
#define VOLSTYLE_BACKGROUND_PLATE 0
#endif

// p(cos) with cos = ω_l·(−ω), from the block's phase (common/phase.glsl).
float phaseFunction(float cosTheta) { return phaseValue(u.phase.x, u.phase.y, cosTheta); }

#include "common/lobes.glsl"

// Whether anything lights the medium (else in-scattering is compiled out).
#define VOLSTYLE_LIT (VOLSTYLE_NUM_LIGHTS > 0 || VOLSTYLE_HAS_LOBES)

#if VOLSTYLE_NUM_LIGHTS > 0
// Optical depth toward each light, stored on the nodes of a light-aligned grid by light_depth.comp
// (core/render/light_grid.h) and interpolated trilinearly between them. Interpolating the depth
// (not the transmittance) is exact for slabs, where the depth is linear.
layout(binding = kUnitLightDepth0) uniform sampler3D s_lightDepth[kLightSlots];

// τ_l(p): the optical depth from index-space point p toward light l.
vec3 lightDepthAt(int l, vec3 p) {
    vec3 g = (u.lightGridFromIndex[l] * vec4(p, 1.0)).xyz;
    return fetchTrilinear(s_lightDepth[l], stencilOn(g, u.lightGridDims[l].xyz));
}

#endif

#if VOLSTYLE_LIT
// L_scat(x, ω) = Σ_l p(ω_l·(−ω)) E_l T_l(x) + the lobes' share, at index-space point p
// (V_l = 1: no occluders).
vec3 inScattering(vec3 p, vec3 dir) {
    vec3 sum = vec3(0.0);
#if VOLSTYLE_NUM_LIGHTS > 0
    for (int l = 0; l < VOLSTYLE_NUM_LIGHTS; ++l)
        sum += phaseFunction(dot(u.lightDirection[l].xyz, -dir)) * u.lightIrradiance[l].rgb * exp(-lightDepthAt(l, p));
#endif
#if VOLSTYLE_HAS_LOBES
    sum += lobeInScattering(p, dir);
#endif
    return sum;
}
#endif

#if VOLSTYLE_HAS_ENVIRONMENT
layout(binding = kUnitEnvironment) uniform sampler2D s_environment;
#endif

// Background radiance seen along ω from pixel `pix`: the view's plate (its pixel), the radiance of
// the lobe whose cell holds ω, the lat-long map (u = 0.5 + atan2(x, -z)/2π, v = acos(y)/π) or the
// constant colour.
vec3 backgroundRadiance(ivec2 pix, vec3 dir) {
#if VOLSTYLE_HAS_ENVIRONMENT && VOLSTYLE_BACKGROUND_PLATE
    return texelFetch(s_environment, pix, 0).rgb;
#elif VOLSTYLE_BACKGROUND_LOBES
    int cell = lobeCellOf(dir);
    return cell < 0 ? u.background.rgb : lobes.radiance[cell].rgb;
#elif VOLSTYLE_HAS_ENVIRONMENT
    vec2 uv = vec2(0.5 + preciseAtan2(dir.x, -dir.z) / (2.0 * kPi),
                   preciseAtan2(length(dir.xz), dir.y) / kPi);
    // Bilinear by hand (texel centres at (i + 0.5) / size, longitude wraps, latitude clamps):
    // texture units quantise filter weights on GPUs, and this is once per pixel.
    ivec2 size = textureSize(s_environment, 0);
    vec2 xy = uv * vec2(size) - 0.5;
    ivec2 i0 = ivec2(floor(xy));
    vec2 f = xy - vec2(i0);
    int x0 = ((i0.x % size.x) + size.x) % size.x, x1 = (x0 + 1) % size.x;
    int y0 = clamp(i0.y, 0, size.y - 1), y1 = clamp(i0.y + 1, 0, size.y - 1);
    vec3 top = mix(texelFetch(s_environment, ivec2(x0, y0), 0).rgb, texelFetch(s_environment, ivec2(x1, y0), 0).rgb, f.x);
    vec3 bottom = mix(texelFetch(s_environment, ivec2(x0, y1), 0).rgb, texelFetch(s_environment, ivec2(x1, y1), 0).rgb, f.x);
    return mix(top, bottom, f.y);
#else
    return u.background.rgb;
#endif
}

// The environment's lobes (core/render/environment_lobes.h, SPEC §8): N directional lights of
// radiance L_i over cells of solid angle Ω_i, each seen through its light volume, the
// transmittance toward it on a grid of its own (core/render/lobe_volumes.h), trilinear between
// nodes. Included by lighting.glsl (after phaseFunction) when VOLSTYLE_HAS_LOBES.
#ifndef VOLSTYLE_HAS_LOBES
#define VOLSTYLE_HAS_LOBES 0
#endif
#ifndef VOLSTYLE_BACKGROUND_LOBES  // the lobes seen directly are the background
#define VOLSTYLE_BACKGROUND_LOBES 0
#endif

#if VOLSTYLE_HAS_LOBES || VOLSTYLE_BACKGROUND_LOBES
layout(std140, binding = kBindingLobeParams) uniform b_LobeParams {
    LobeParams lobes;
};
#endif

#if VOLSTYLE_BACKGROUND_LOBES
// The lobe whose cell holds direction ω: the nearest centre (LobeBasis::cellOf), none (−1) below
// the horizon of a hemisphere basis. u.background.w = ±count (− for the hemisphere).
int lobeCellOf(vec3 dir) {
    int count = int(abs(u.background.w));
    if (u.background.w < 0.0 && dir.y < 0.0) return -1;
    int best = 0;
    float bestDot = -2.0;
    for (int i = 0; i < count; ++i) {
        float d = dot(lobes.direction[i].xyz, dir);
        if (d > bestDot) bestDot = d, best = i;
    }
    return best;
}
#endif

#if VOLSTYLE_HAS_LOBES
layout(binding = kUnitLobeTransmittance) uniform samplerBuffer s_lobeTransmittance;

// The 8 light-volume nodes around an index-space point: each node's first value (lobe 0,
// channel 0) and the trilinear fractions. Named fields: llvmpipe keeps arrays in memory.
struct LobeStencil {
    int n000, n100, n010, n110, n001, n101, n011, n111;
    vec3 f;
};

LobeStencil lobeStencilAt(vec3 p) {
    ivec3 n = u.lobeGrid.xyz;
    vec3 q = clamp((p + 0.5) * u.lobeScale.xyz - 0.5, vec3(0.0), vec3(n - 1));
    ivec3 i0 = min(ivec3(floor(q)), n - 1), i1 = min(i0 + 1, n - 1);
    int stride = u.lobeGrid.w * int(u.lobeScale.w);
    int r00 = (i0.z * n.y + i0.y) * n.x, r10 = (i0.z * n.y + i1.y) * n.x;
    int r01 = (i1.z * n.y + i0.y) * n.x, r11 = (i1.z * n.y + i1.y) * n.x;
    LobeStencil s;
    s.n000 = (r00 + i0.x) * stride, s.n100 = (r00 + i1.x) * stride;
    s.n010 = (r10 + i0.x) * stride, s.n110 = (r10 + i1.x) * stride;
    s.n001 = (r01 + i0.x) * stride, s.n101 = (r01 + i1.x) * stride;
    s.n011 = (r11 + i0.x) * stride, s.n111 = (r11 + i1.x) * stride;
    s.f = q - vec3(i0);
    return s;
}

float lobeTrilinear(LobeStencil s, int k) {
    float c00 = mix(texelFetch(s_lobeTransmittance, s.n000 + k).r, texelFetch(s_lobeTransmittance, s.n100 + k).r, s.f.x);
    float c10 = mix(texelFetch(s_lobeTransmittance, s.n010 + k).r, texelFetch(s_lobeTransmittance, s.n110 + k).r, s.f.x);
    float c01 = mix(texelFetch(s_lobeTransmittance, s.n001 + k).r, texelFetch(s_lobeTransmittance, s.n101 + k).r, s.f.x);
    float c11 = mix(texelFetch(s_lobeTransmittance, s.n011 + k).r, texelFetch(s_lobeTransmittance, s.n111 + k).r, s.f.x);
    return mix(mix(c00, c10, s.f.y), mix(c01, c11, s.f.y), s.f.z);
}

// T_i(p): the transmittance toward lobe i.
vec3 lobeTransmittance(LobeStencil s, int lobe) {
    if (u.lobeScale.w < 1.5) return vec3(lobeTrilinear(s, lobe));
    return vec3(lobeTrilinear(s, 3 * lobe), lobeTrilinear(s, 3 * lobe + 1), lobeTrilinear(s, 3 * lobe + 2));
}

// What lobe i adds to L_scat per unit radiance along view direction ω: p(ω_i·(−ω)) Ω_i T_i(p)
// (one column of the lights unknown's T before the segment's weight and albedo).
vec3 lobeResponse(LobeStencil s, int lobe, vec3 dir) {
    vec4 d = lobes.direction[lobe];
    return phaseFunction(dot(d.xyz, -dir)) * d.w * lobeTransmittance(s, lobe);
}

// Σ_i L_i p(ω_i·(−ω)) Ω_i T_i(p): the lobes' in-scattering at index-space point p.
vec3 lobeInScattering(vec3 p, vec3 dir) {
    LobeStencil s = lobeStencilAt(p);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < u.lobeGrid.w; ++i) sum += lobes.radiance[i].rgb * lobeResponse(s, i, dir);
    return sum;
}
#endif

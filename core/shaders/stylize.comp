// The stylizer's per-pixel pass (SPEC §7, the GI paper Eq. 2): for the view ray x_t = e + tω up to
// its first surface at distance s (or the camera's far), the average visibility
//   V̄ = (1/s) ∫₀ˢ V(x_t) dt      (naive: u.imageSize.w midpoint lookups of the shadow map)
// and the frame L = L_surf e^{−σt s} + L_scat with, for a directional light,
//   L_scat = ρ p(ω_l·(−ω)) E (1 − e^{−σt s}) V̄.
// Surfaces are lit by the light, shadowed by the (unmodified) shadow map, plus the background
// as ambient (a white diffuse surface under a uniform sky of radiance B reflects B). A transfer
// function F(V̄, d) then multiplies or replaces L_scat (SPEC §7).
#include "common/stylize_params.glsl"
#include "common/pinhole.glsl"
#include "common/phase.glsl"

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

layout(binding = kUnitShadowDepth) uniform sampler2D s_shadowDepth;
layout(binding = kUnitGBufferSurface) uniform sampler2D s_surface;
layout(binding = kUnitGBufferColour) uniform sampler2D s_colour;
layout(binding = kUnitTransferFunction) uniform sampler2D s_transfer;

layout(std430, binding = kBindingImageOut) writeonly buffer b_Image {
    vec4 pixels[];
};
layout(std430, binding = kBindingLayersOut) writeonly buffer b_Layers {
    vec4 layers[];  // layer k of pixel p at k * pixelCount + p (kStylizeLayers)
};
layout(std430, binding = kBindingScatterDepth) readonly buffer b_ScatterDepth {
    float scatterDepth[];  // the shadow map after the occluders' manipulations, for V̄ only
};

// V(x): 1 where the light reaches world point x, by the unmodified map (surfaces) or the
// manipulated one (the scattering). Outside the map's footprint nothing occludes (every occluder
// lies inside it); a point nearer the light than the map's near plane is lit.
float visibility(vec3 x, bool manipulated) {
    if (u.shadow.y < 0.5) return 1.0;
    vec3 c = (u.lightFromWorld * vec4(x, 1.0)).xyz;
    if (any(greaterThan(abs(c.xy), vec2(1.0)))) return 1.0;
    int n = u.imageSize.z;
    ivec2 texel = clamp(ivec2(floor((c.xy * 0.5 + 0.5) * float(n))), ivec2(0), ivec2(n - 1));
    float occluder = manipulated ? scatterDepth[texel.y * n + texel.x] : texelFetch(s_shadowDepth, texel, 0).r;
    // Depth 1 is nothing there; a point past the far plane is shadowed only by what was drawn.
    return occluder >= 1.0 || c.z * 0.5 + 0.5 <= occluder + u.shadow.x ? 1.0 : 0.0;
}

// F(V̄, d): bilinear between texel centres by hand (texture units quantise filter weights on
// GPUs), clamped; image row 0 is the top, d = 1.
vec4 transferFunction(float vBar, float d) {
    ivec2 size = textureSize(s_transfer, 0);
    vec2 xy = vec2(clamp(vBar, 0.0, 1.0) * float(size.x), (1.0 - clamp(d, 0.0, 1.0)) * float(size.y)) - 0.5;
    xy = clamp(xy, vec2(0.0), vec2(size - 1));
    ivec2 i0 = ivec2(floor(xy)), i1 = min(i0 + 1, size - 1);
    vec2 f = xy - vec2(i0);
    vec4 top = mix(texelFetch(s_transfer, i0, 0), texelFetch(s_transfer, ivec2(i1.x, i0.y), 0), f.x);
    vec4 bottom = mix(texelFetch(s_transfer, ivec2(i0.x, i1.y), 0), texelFetch(s_transfer, i1, 0), f.x);
    return mix(top, bottom, f.y);
}

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = u.imageSize.xy;
    if (pix.x >= size.x || pix.y >= size.y) return;
    vec3 dir = pinholeRay(pix, size, u.camForward, u.camRight, u.camUp.xyz);
    ivec2 texel = ivec2(pix.x, size.y - 1 - pix.y);  // the framebuffer's row 0 is at the bottom
    vec4 surface = texelFetch(s_surface, texel, 0);
    bool hit = surface.w > 0.0;
    float s = hit ? min(surface.w, u.background.w) : u.background.w;

    // Average visibility along the ray (Eq. 2's factored-out V̄).
    int steps = max(u.imageSize.w, 1);
    float visible = 0.0;
    for (int i = 0; i < steps; ++i) visible += visibility(u.eye.xyz + ((float(i) + 0.5) / float(steps)) * s * dir, true);
    float vBar = visible / float(steps);

    // Single scattering with the visibility factored out: ρ p E (1 − e^{−σt s}) V̄.
    vec3 light = u.lightDirection.xyz;
    float sigma = u.medium.x;
    float opacity = 1.0 - exp(-sigma * s);
    vec3 scattering = u.medium.y * phaseValue(u.medium.z, u.medium.w, dot(light, -dir)) * u.irradiance.rgb * opacity * vBar;

    // The transfer function over (V̄, linear depth): multiply, or replace the scattering.
    vec3 styled = scattering;
    if (u.transfer.x > 0.5) {
        vec4 F = transferFunction(vBar, (s - u.transfer.y) / (u.transfer.z - u.transfer.y));
        styled = u.transfer.x < 1.5 ? F.rgb * scattering : F.rgb * F.a;
    }

    vec3 behind = u.background.rgb;
    if (hit) {
        vec3 albedo = texelFetch(s_colour, texel, 0).rgb;
        vec3 n = normalize(surface.xyz);
        if (dot(n, dir) > 0.0) n = -n;  // leaves are seen from both sides
        vec3 x = u.eye.xyz + s * dir;
        // Offset along the normal by 1.5 shadow-map texels (u.shadow.z, world units): no acne.
        float lit = visibility(x + (1.5 * u.shadow.z + 1e-4 * s) * n, false) * max(dot(n, light), 0.0);
        behind = albedo * (u.irradiance.rgb * lit * (1.0 / 3.14159265358979) + u.background.rgb);
    }
    int p = pix.y * size.x + pix.x;
    pixels[p] = vec4(behind * exp(-sigma * s) + styled, 1.0);
    int count = size.x * size.y;
    layers[p] = vec4(scattering, vBar);
    layers[count + p] = vec4(s, hit ? 1.0 : 0.0, 0.0, 0.0);
}

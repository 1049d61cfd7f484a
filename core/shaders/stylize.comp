// The stylizer's per-pixel pass (SPEC §7, the GI paper Eq. 2): for the view ray x_t = e + tω up to
// its first surface at distance s (or the camera's far), the average visibility
//   V̄ = (1/s) ∫₀ˢ V(x_t) dt      (naive: u.imageSize.w midpoint lookups of the shadow map)
// and the frame L = L_surf e^{−σt s} + L_scat with, for a directional light,
//   L_scat = ρ p(ω_l·(−ω)) E (1 − e^{−σt s}) V̄.
// Surfaces are lit by the light, shadowed by the (unmodified) shadow map, plus the background
// as ambient (a white diffuse surface under a uniform sky of radiance B reflects B). A transfer
// function F(V̄, d) then multiplies or replaces L_scat (SPEC §7).
// With a heterogeneous medium (u.volumeLo.w > 0; issue #15, beyond the paper) σt(x) comes from a
// grid over a box and the ray's part in the box is marched: with τ(t) = ∫₀ᵗ σt,
//   L_scat = ρ (∫ σt e^{−τ} L_e dt) V̄,   V̄ = ∫ σt V T_l dt / ∫ σt dt,
// L_e = p E (directional; a spot's I·cone/d²·p per sample), T_l the grid's transmittance toward
// the light (stylize_transmittance.comp), and surfaces behind are dimmed by e^{−τ(s)} and lit
// through T_l. A constant grid filling the box gives the homogeneous formula back (docs/STYLIZER.md).
#include "common/stylize_params.glsl"
#include "common/pinhole.glsl"
#include "common/phase.glsl"
#include "common/min_max_entry.glsl"
#include "common/ray_box.glsl"
#include "common/stylize_medium.glsl"
#include "common/march_segments.glsl"

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

layout(binding = kUnitShadowDepth) uniform sampler2D s_shadowDepth;
layout(binding = kUnitGBufferSurface) uniform sampler2D s_surface;
layout(binding = kUnitGBufferColour) uniform sampler2D s_colour;
layout(binding = kUnitTransferFunction) uniform sampler2D s_transfer;
layout(binding = kUnitStylizeTransmittance) uniform sampler3D s_lightDepth;  // τ_l: optical depth toward the light
layout(binding = kUnitStylizeOccupancy) uniform sampler3D s_occupancy;

layout(std430, binding = kBindingImageOut) writeonly buffer b_Image {
    vec4 pixels[];
};
layout(std430, binding = kBindingLayersOut) writeonly buffer b_Layers {
    vec4 layers[];  // layer k of pixel p at k * pixelCount + p (kStylizeLayers)
};
layout(std430, binding = kBindingScatterDepth) readonly buffer b_ScatterDepth {
    float scatterDepth[];  // the shadow map after the occluders' manipulations, for V̄ only
};

layout(std430, binding = kBindingMinMax) readonly buffer b_MinMax {
    uint minMax[];  // b_ScatterDepth again, with its min-max levels after it (common/min_max_entry.glsl)
};

// Depths are the light's clip depth in [0, 1]; 1 is nothing there. A point is lit where it lies
// no deeper than the occluder (plus the bias); past the far plane only what was drawn shadows.
bool litAgainst(float z, float occluder) { return occluder >= 1.0 || z <= occluder + u.shadow.x; }
float depth01(vec4 h) { return h.z / h.w * 0.5 + 0.5; }

// The texel of an n×n map under a position in texel units, clamped to the map (rounding at its rim).
ivec2 mapTexel(vec2 position, int n) { return clamp(ivec2(floor(position)), ivec2(0), ivec2(n - 1)); }

// V(x): 1 where the light reaches world point x, by the unmodified map (surfaces) or the
// manipulated one (the scattering). The light's clip space is homogeneous (w = 1 for a
// directional light's orthographic map, perspective for a spot). Outside the map's footprint
// nothing occludes (every occluder lies inside it; outside a spot's cone there is no light).
float visibility(vec3 x, bool manipulated) {
    if (u.shadow.y < 0.5) return 1.0;
    vec4 h = u.lightFromWorld * vec4(x, 1.0);
    if (h.w <= 0.0) return 1.0;
    vec3 c = h.xyz / h.w;
    if (any(greaterThan(abs(c.xy), vec2(1.0)))) return 1.0;
    int n = u.imageSize.z;
    ivec2 texel = mapTexel((c.xy * 0.5 + 0.5) * float(n), n);
    float occluder = manipulated ? scatterDepth[texel.y * n + texel.x] : texelFetch(s_shadowDepth, texel, 0).r;
    return litAgainst(c.z * 0.5 + 0.5, occluder) ? 1.0 : 0.0;
}

// The naive V̄: `steps` midpoint lookups along t ∈ [0, s] (the reference).
float averageVisibilityNaive(vec3 e, vec3 dir, float s) {
    int steps = max(u.imageSize.w, 1);
    float visible = 0.0;
    for (int i = 0; i < steps; ++i) visible += visibility(e + ((float(i) + 0.5) / float(steps)) * s * dir, true);
    return visible / float(steps);
}

// The side of min-max level `level` of an n×n map (shadow_minmax.comp: odd sides round up).
int mipSide(int n, int level) { return (n + (1 << level) - 1) >> level; }

// t where the ray's projective coordinate (a0 + t a1) / (w0 + t w1) equals `target`.
float crossingT(float a0, float a1, float w0, float w1, float target) {
    float den = a1 - target * w1;
    return abs(den) < 1e-30 ? 3.0e38 : (target * w0 - a0) / den;
}

// Keeps the part of [ta, tb] where f0 + t f1 ≥ 0.
void clipToHalfSpace(float f0, float f1, inout float ta, inout float tb) {
    if (abs(f1) < 1e-30) {
        if (f0 < 0.0) tb = ta;
    } else if (f1 > 0.0) {
        ta = max(ta, -f0 / f1);
    } else {
        tb = min(tb, -f0 / f1);
    }
}

// The accelerated V̄: the exact lit share of the view ray against the (nearest-texel) manipulated
// map, found by descending its min-max mipmap. Along the ray the light-clip position is
// h(t) = h0 + t h1, so every texel coordinate and the depth are monotone in t between w > 0, and
// each crossing is one division. A cell whose minimum lies behind the ray's deepest point over it
// is wholly lit, one whose maximum lies in front of its shallowest point wholly in shadow; only
// cells the ray crosses an occluder's depth in are opened, down to single texels, where the lit
// part of the stretch is solved for in closed form. The cost follows the number of shadow edges
// along the ray, not its length (Chen et al. 2011 with the 2D mipmap instead of an epipolar
// rectification; docs/STYLIZER.md says why).
float averageVisibilityMinMax(vec3 e, vec3 dir, float s) {
    if (u.shadow.y < 0.5 || s <= 0.0) return 1.0;
    vec4 h0 = u.lightFromWorld * vec4(e, 1.0), h1 = u.lightFromWorld * vec4(dir, 0.0);
    float ta = 0.0, tb = s;
    clipToHalfSpace(h0.w - 1e-7, h1.w, ta, tb);  // in front of a spot (always, for w = 1)
    clipToHalfSpace(h0.w - h0.x, h1.w - h1.x, ta, tb);  // x ≤ w
    clipToHalfSpace(h0.w + h0.x, h1.w + h1.x, ta, tb);  // −x ≤ w
    clipToHalfSpace(h0.w - h0.y, h1.w - h1.y, ta, tb);
    clipToHalfSpace(h0.w + h0.y, h1.w + h1.y, ta, tb);
    if (!(tb > ta)) return 1.0;
    int n = u.imageSize.z;
    float fn = float(n);
    // Which way x/w, y/w and z/w move with t (constant: the numerators of their derivatives).
    float sx = sign(h1.x * h0.w - h0.x * h1.w), sy = sign(h1.y * h0.w - h0.y * h1.w);
    float sz = sign(h1.z * h0.w - h0.z * h1.w);
    float lit = s - (tb - ta);  // outside the footprint nothing occludes
    int top = u.options.y - 1, level = top;
    float t = ta, tiny = 1e-6 * s;
    for (int iter = 0; iter < 65536 && t < tb; ++iter) {
        vec4 h = h0 + t * h1;
        // The cell the ray is in just after t (nudged a thousandth of a texel along its motion).
        vec2 texel = (h.xy / h.w * 0.5 + 0.5) * fn + vec2(sx, sy) * 1e-3;
        int cellSize = 1 << level, side = mipSide(n, level);
        ivec2 cell = ivec2(floor(texel / float(cellSize)));
        // Where the ray leaves the cell; a crossing at or before t is the projective line's other
        // branch (behind a spot, w < 0): that bound is never reached.
        float tExit = tb;
        float cx = sx == 0.0 ? tb : crossingT(h0.x, h1.x, h0.w, h1.w, float((cell.x + (sx > 0.0 ? 1 : 0)) * cellSize) * 2.0 / fn - 1.0);
        float cy = sy == 0.0 ? tb : crossingT(h0.y, h1.y, h0.w, h1.w, float((cell.y + (sy > 0.0 ? 1 : 0)) * cellSize) * 2.0 / fn - 1.0);
        if (cx > t) tExit = min(tExit, cx);
        if (cy > t) tExit = min(tExit, cy);
        tExit = min(max(tExit, t + tiny), tb);
        bool inside = all(greaterThanEqual(cell, ivec2(0))) && all(lessThan(cell, ivec2(side)));
        vec2 mm = inside ? minMaxOfEntry(minMax[u.mipOffset[level / 4][level % 4] + cell.y * side + cell.x], level == 0) : vec2(1.0);
        float zA = depth01(h), zB = depth01(h0 + tExit * h1);
        float zLo = min(zA, zB), zHi = max(zA, zB);
        if (mm.x >= 1.0 || zHi <= mm.x + u.shadow.x) {
            lit += tExit - t;  // in front of everything in the cell (or it is empty)
        } else if (mm.y < 1.0 && zLo > mm.y + u.shadow.x) {
            // behind everything in the cell: in shadow
        } else if (level == 0) {
            // One texel, one depth D: lit where z(t) ≤ D + bias, on one side of a single crossing.
            float limit = mm.x + u.shadow.x;
            float tc = crossingT(h0.z, h1.z, h0.w, h1.w, 2.0 * limit - 1.0);
            float len = tExit - t;
            lit += sz > 0.0 ? clamp(tc - t, 0.0, len) : sz < 0.0 ? clamp(tExit - tc, 0.0, len) : (zA <= limit ? len : 0.0);
        } else {
            level -= 1;  // undecided: open the cell
            continue;
        }
        // Go up a level only on leaving the parent: a sibling's parent is the one just opened.
        t = tExit;
        if (level < top) {
            vec4 hNext = h0 + t * h1;
            vec2 next = (hNext.xy / hNext.w * 0.5 + 0.5) * fn + vec2(sx, sy) * 1e-3;
            if (ivec2(floor(next / float(2 * cellSize))) != (cell >> 1)) level += 1;
        }
    }
    return clamp(lit / s, 0.0, 1.0);
}

// The same traversal for the directional light's orthographic map, where everything is affine
// in t (w = 1): texel(t) = a + t b and z(t) = z0 + t dz, so a crossing is one multiply by a
// reciprocal computed once per ray. Cell and parent follow from integer shifts.
float averageVisibilityMinMaxOrtho(vec3 e, vec3 dir, float s) {
    if (u.shadow.y < 0.5 || s <= 0.0) return 1.0;
    vec4 h0 = u.lightFromWorld * vec4(e, 1.0), h1 = u.lightFromWorld * vec4(dir, 0.0);
    float ta = 0.0, tb = s;
    clipToHalfSpace(1.0 - h0.x, -h1.x, ta, tb);
    clipToHalfSpace(1.0 + h0.x, h1.x, ta, tb);
    clipToHalfSpace(1.0 - h0.y, -h1.y, ta, tb);
    clipToHalfSpace(1.0 + h0.y, h1.y, ta, tb);
    if (!(tb > ta)) return 1.0;
    // Walk the stretch [0, len0] from whichever end makes the depth grow: V̄ does not depend on the
    // direction, and then a cell's depth range along the ray is [z(t), z(tExit)].
    float len0 = tb - ta;
    if (h1.z < 0.0) {
        h0 += tb * h1;
        h1 = -h1;
    } else {
        h0 += ta * h1;
    }
    int n = u.imageSize.z;
    float fn = float(n);
    vec2 a = (h0.xy * 0.5 + 0.5) * fn, b = h1.xy * 0.5 * fn;
    // z0 carries the bias: a texel of depth D lights the ray where z(t) − bias ≤ D.
    float z0 = h0.z * 0.5 + 0.5 - u.shadow.x, dz = h1.z * 0.5;
    vec2 sgn = sign(b);
    bvec2 moves = greaterThan(abs(b), vec2(1e-20));
    // A cell's exit along an axis is (bound − a) / b; an axis the ray does not move along never
    // bounds it: (bound + 1e9) · 1e20 lies past any stretch, and stays finite however a compiler
    // rearranges it.
    vec2 invB = vec2(moves.x ? 1.0 / b.x : 1.0e20, moves.y ? 1.0 / b.y : 1.0e20);
    vec2 aExit = vec2(moves.x ? a.x : -1.0e9, moves.y ? a.y : -1.0e9);
    ivec2 ahead = ivec2(greaterThan(sgn, vec2(0.0)));
    vec2 aNudged = a + sgn * 1e-3;
    float invDz = dz > 1e-30 ? 1.0 / dz : 0.0;
    float lit = s - len0;
    int top = u.options.y - 1;
    // Start where the cells are larger than the stretch's extent on the map, E texels: 2^k > ⌊E⌋ + 1
    // (at most two levels above the finest that holds it). Any level gives a correct walk; this one
    // skips opening the levels above.
    vec2 extent = abs(b) * len0;
    int level = min(top, findMSB(int(max(extent.x, extent.y)) + 1) + 1);
    // The least step: a millionth of the stretch (of the whole ray, a step could skip texels of a
    // short stretch on a long ray).
    float t = 0.0, tiny = 1e-6 * len0, zA = z0;
    // Texels are clamped to the map where they are found: the footprint clip keeps the stretch on
    // it, so a texel off it is rounding (or the nudge) at its rim, and every cell of a clamped texel
    // is then on its level (no clamp per step).
    ivec2 texel = mapTexel(aNudged, n);
    int side = mipSide(n, level), offset = u.mipOffset[level >> 2][level & 3];
    for (int iter = 0; iter < 65536 && t < len0; ++iter) {
        ivec2 cell = texel >> level;
        vec2 exits = (vec2((cell + ahead) << level) - aExit) * invB;
        float tExit = min(max(min(exits.x, exits.y), t + tiny), len0);
        vec2 mm = minMaxOfEntry(minMax[offset + cell.y * side + cell.x], level == 0);
        float zB = z0 + tExit * dz;
        if (zB <= mm.x || mm.x >= 1.0) {
            lit += tExit - t;
        } else if (zA > mm.y && mm.y < 1.0) {
        } else if (level == 0) {
            // One texel, depth D: lit up to where z(t) − bias = D (z grows along the walk).
            lit += dz > 1e-30 ? clamp((mm.x - z0) * invDz - t, 0.0, tExit - t) : (zA <= mm.x ? tExit - t : 0.0);
        } else {
            level -= 1;  // undecided: open the cell
            side = mipSide(n, level);
            offset -= side * side;
            continue;
        }
        t = tExit;
        zA = zB;
        // The bits of the texel that the step changed: the parent (level + 1) changed with any above.
        ivec2 moved = texel ^ mapTexel(aNudged + t * b, n);
        texel ^= moved;
        if (level < top && ((moved.x | moved.y) >> (level + 1)) != 0) {
            offset += side * side;
            level += 1;
            side = mipSide(n, level);
        }
    }
    return clamp(lit / s, 0.0, 1.0);
}

// The spot's in-scattering integral ∫₀ˢ σt ρ p(θ) e^{−σt t} L_ei(x_t) dt without visibility,
// L_ei = I·cone/d²·e^{−σt d} (d: distance to the light), by the midpoint rule over u.options.w steps.
vec3 spotInScattering(vec3 e, vec3 dir, float s) {
    int k = max(u.options.w, 1);
    float sigma = u.medium.x, dt = s / float(k);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < k; ++i) {
        float t = (float(i) + 0.5) * dt;
        vec3 toLight = u.spot.xyz - (e + t * dir);
        float d = max(length(toLight), 1e-6);
        vec3 l = toLight / d;
        float cone = smoothstep(u.spot.w, u.spotCone.x, dot(l, u.lightDirection.xyz));
        sum += exp(-sigma * (t + d)) * phaseValue(u.medium.z, u.medium.w, dot(l, -dir)) * cone / (d * d);
    }
    return sigma * u.medium.y * dt * sum * u.irradiance.rgb;
}

// What reaches a surface point x from the light, before its shadow and cosine: E for the
// directional light; I·cone/d²·e^{−σt d} for a spot. `l` returns the unit direction toward it.
vec3 incidentAt(vec3 x, out vec3 l) {
    if (u.options.z != kStylizerLightSpot) {
        l = u.lightDirection.xyz;
        return u.irradiance.rgb;
    }
    vec3 toLight = u.spot.xyz - x;
    float d = max(length(toLight), 1e-6);
    l = toLight / d;
    float cone = smoothstep(u.spot.w, u.spotCone.x, dot(l, u.lightDirection.xyz));
    return u.irradiance.rgb * cone * exp(-u.medium.x * d) / (d * d);
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

bool insideVolume(vec3 x) { return all(greaterThanEqual(x, u.volumeLo.xyz)) && all(lessThanEqual(x, u.volumeHi.xyz)); }
// T_l at x: the grid's transmittance toward the light, e^{−τ_l} (1 when it is off). Outside the
// box, the ray toward the light may cross it: then τ_l where it enters (the same ray onward), so a
// cloud shadows the ground under it.
float lightTransmittance(vec3 x) {
    if (u.volumeHi.w < 0.5) return 1.0;
    if (insideVolume(x)) return exp(-texture(s_lightDepth, volumeUvw(x)).r);
    vec3 l = u.lightDirection.xyz;
    float reach = 3.0e38;
    if (u.options.z == kStylizerLightSpot) {
        reach = length(u.spot.xyz - x);
        l = (u.spot.xyz - x) / max(reach, 1e-30);
    }
    vec2 span = rayBox(x, safeInverse(l), u.volumeLo.xyz, u.volumeHi.xyz);
    if (!(span.y > span.x && span.x > 0.0 && span.x < reach)) return 1.0;
    return exp(-texture(s_lightDepth, volumeUvw(x + span.x * l)).r);
}

// What the light gives a point x of the medium before visibility, per unit of σt e^{−τ}: p E for
// the directional light, I·cone/d²·p for a spot (no homogeneous attenuation: T_l is in V̄).
vec3 emittedTowardEye(vec3 x, vec3 dir) {
    if (u.options.z != kStylizerLightSpot)
        return u.irradiance.rgb * phaseValue(u.medium.z, u.medium.w, dot(u.lightDirection.xyz, -dir));
    vec3 toLight = u.spot.xyz - x;
    float d = max(length(toLight), 1e-6);
    vec3 l = toLight / d;
    float cone = smoothstep(u.spot.w, u.spotCone.x, dot(l, u.lightDirection.xyz));
    return u.irradiance.rgb * cone / (d * d) * phaseValue(u.medium.z, u.medium.w, dot(l, -dir));
}

// Marches the view ray's part in the box, [0, s] clipped to it, at u.volumeLo.w equal segments' midpoints:
// V̄ (−1 when the ray meets no medium), ∫σt e^{−τ} L_e dt and e^{−τ(s)}.
void marchVolume(vec3 e, vec3 dir, float s, out float vBar, out vec3 inScattered, out float transmittance) {
    vBar = -1.0;
    inScattered = vec3(0.0);
    transmittance = 1.0;
    vec2 span = rayBox(e, safeInverse(dir), u.volumeLo.xyz, u.volumeHi.xyz);
    float ta = max(span.x, 0.0), tb = min(span.y, s);
    if (!(tb > ta)) return;
    int steps = int(u.volumeLo.w);
    Segments seg = Segments(ta, (tb - ta) / float(steps), steps);
    // The volume's index space (voxel centres at integers over the box), where its occupancy
    // bricks are: empty ones are crossed in one go, the midpoints staying those of the uniform
    // march (common/march_segments.glsl), so skipping changes nothing but the time.
    vec3 voxels = vec3(textureSize(s_density, 0)), size = u.volumeHi.xyz - u.volumeLo.xyz;
    vec3 o = (e - u.volumeLo.xyz) / size * voxels - 0.5, d = dir * voxels / size;
    ivec3 bricks = textureSize(s_occupancy, 0);
    float tau = 0.0, weighted = 0.0, weights = 0.0;
    for (int i = 0; i < steps;) {
        int next = skipEmptyBricksOn(s_occupancy, bricks, i, seg, o, d);
        if (next != i) {
            i = next;
            continue;
        }
        vec3 x = e + segmentMidpoint(seg, i++) * dir;
        float w = densityAt(volumeUvw(x)) * seg.dt;  // σt dt
        if (w <= 0.0) continue;
        weighted += w * visibility(x, true) * lightTransmittance(x);
        weights += w;
        inScattered += exp(-tau) * (1.0 - exp(-w)) * emittedTowardEye(x, dir);  // exact for σt constant over the step
        tau += w;
    }
    transmittance = exp(-tau);
    if (weights > 0.0) vBar = weighted / weights;
}

float averageVisibility(vec3 dir, float s) {
    if (u.options.x != kVisibilityMinMax) return averageVisibilityNaive(u.eye.xyz, dir, s);
    return u.options.z == kStylizerLightSpot ? averageVisibilityMinMax(u.eye.xyz, dir, s) : averageVisibilityMinMaxOrtho(u.eye.xyz, dir, s);
}

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy) + u.pixelOrigin.xy;
    ivec2 size = u.imageSize.xy;
    if (pix.x >= size.x || pix.y >= size.y) return;
    vec3 dir = pinholeRay(pix, size, u.camForward, u.camRight, u.camUp.xyz);
    ivec2 texel = ivec2(pix.x, size.y - 1 - pix.y);  // the framebuffer's row 0 is at the bottom
    vec4 surface = texelFetch(s_surface, texel, 0);
    bool hit = surface.w > 0.0;
    float s = hit ? min(surface.w, u.background.w) : u.background.w;

    // Average visibility along the ray (Eq. 2's factored-out V̄).
    float sigma = u.medium.x;
    vec3 scattering;
    float vBar, viewTransmittance;
    if (u.volumeLo.w > 0.0) {
        vec3 inScattered;
        marchVolume(u.eye.xyz, dir, s, vBar, inScattered, viewTransmittance);
        if (vBar < 0.0) vBar = averageVisibility(dir, s);  // no medium on the ray: the geometric V̄ (for the TF)
        scattering = u.medium.y * inScattered * vBar;
    } else if (u.options.z == kStylizerLightSpot) {
        // Single scattering with the visibility factored out: ρ p E (1 − e^{−σt s}) V̄ (directional),
        // the numerical integral times V̄ (spot).
        vBar = averageVisibility(dir, s);
        viewTransmittance = exp(-sigma * s);
        scattering = spotInScattering(u.eye.xyz, dir, s) * vBar;
    } else {
        vBar = averageVisibility(dir, s);
        viewTransmittance = exp(-sigma * s);
        vec3 light = u.lightDirection.xyz;
        float opacity = 1.0 - exp(-sigma * s);
        scattering = u.medium.y * phaseValue(u.medium.z, u.medium.w, dot(light, -dir)) * u.irradiance.rgb * opacity * vBar;
    }

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
        vec3 light;
        vec3 incident = incidentAt(x, light);
        // A spot's texels grow with the distance from it (u.shadow.z is then per unit distance).
        float texelSize = u.options.z == kStylizerLightSpot ? u.shadow.z * distance(x, u.spot.xyz) : u.shadow.z;
        float lit = visibility(x + (1.5 * texelSize + 1e-4 * s) * n, false) * max(dot(n, light), 0.0);
        if (u.volumeLo.w > 0.0) lit *= lightTransmittance(x);
        behind = albedo * (incident * lit * (1.0 / 3.14159265358979) + u.background.rgb);
    }
    int p = pix.y * size.x + pix.x;
    pixels[p] = vec4(behind * viewTransmittance + styled, 1.0);
    int count = size.x * size.y;
    layers[p] = vec4(scattering, vBar);
    layers[count + p] = vec4(s, hit ? 1.0 : 0.0, 0.0, 0.0);
}

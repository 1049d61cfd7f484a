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

// Catmull–Rom weights of the four nodes around fraction t.
vec4 catmullRomWeights(float t) {
    float t2 = t * t, t3 = t2 * t;
    return vec4(-0.5 * t3 + t2 - 0.5 * t, 1.5 * t3 - 2.5 * t2 + 1.0, -1.5 * t3 + 2.0 * t2 + 0.5 * t, 0.5 * t3 - 0.5 * t2);
}

// The light depth on node plane g.z (an integer) at (g.x, g.y). A light along a voxel axis puts the
// nodes on voxel centres, where the depth of trilinear extinction is bilinear between nodes: read
// bilinearly (exact). Otherwise its kinks fall between nodes and the depth is smoother across the
// beam than bilinear reading makes it: a Catmull–Rom spline over the 4×4 nodes around the point,
// held to the range of the 2×2 nearest (no overshoot at shadow edges). Issue #34: on clouds of
// 0.6–4 optical depths a voxel lit from the side or at a grazing angle this takes the image's RMS
// against the exact light integral from 1.8–3.1% to 0.5–1.5% (bench/light_depth_bench).
vec3 lightDepthOnPlane(sampler3D tex, vec3 g, ivec4 dims) {
    Stencil s = stencilOn(g, dims.xyz);
    if (dims.w != 0) return fetchTrilinear(tex, s);
    vec4 wx = catmullRomWeights(s.f.x), wy = catmullRomWeights(s.f.y);
    int plane = clamp(int(round(g.z)), 0, dims.z - 1);  // g.z is a node plane up to rounding
    vec3 sum = vec3(0.0), lo = vec3(3e38), hi = vec3(-3e38);
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
            ivec3 node = ivec3(clamp(s.i0.xy + ivec2(a - 1, b - 1), ivec2(0), dims.xy - 1), plane);
            vec3 v = texelFetch(tex, node, 0).rgb;
            sum += wx[a] * wy[b] * v;
            if (a == 1 || a == 2)
                if (b == 1 || b == 2) lo = min(lo, v), hi = max(hi, v);
        }
    return clamp(sum, lo, hi);
}

// τ_l(p): the optical depth from index-space point p toward light l. Near p it is marched from p
// itself: the grid cannot follow a dense medium's rise within a node (up to 4 optical depths a
// voxel, issue #34: 31% off on a dense backlit cloud), and what a sample sees is decided there.
// The march runs toward the light to the node planes across the beam (planes c = const of the
// grid), for at least kLightMarchMinNodes, on while the last span was dense, and then adds the
// grid's depth on the plane it stopped at (lightDepthOnPlane). A ray that leaves the voxels' box on
// the way needs no grid; one that has gathered kLightMarchOpaque is dark. Thin media pay 2–4
// samples, dense ones up to 2·(kLightMarchMaxSpans + 1) at a step of 0.5 voxel.
vec3 lightDepthAt(int l, vec3 p) {
    mat4 gridFromIndex = u.lightGridFromIndex[l];
    vec3 g = (gridFromIndex * vec4(p, 1.0)).xyz;
    vec3 row = vec3(gridFromIndex[0][2], gridFromIndex[1][2], gridFromIndex[2][2]);  // ∇(grid z): away from the light
    float nodesPerIndex2 = dot(row, row);
    vec3 toLight = -row / nodesPerIndex2;  // index-space step of one node toward the light
    float nodeVoxels = inversesqrt(nodesPerIndex2);
    float worldPerNode = nodeVoxels / length(mat3(u.indexFromWorld) * u.lightDirection[l].xyz);
    float stepsPerNode = nodeVoxels / u.march.x;
    float exitNodes = max(intersectVolumeBox(p, toLight).y, 0.0);

    vec3 tau = vec3(0.0);
    float s0 = 0.0, s1 = g.z - floor(g.z);  // this span: [s0, s1] nodes toward the light from p
    float gridAt = -1.0;                    // where the grid takes over (nodes from p), if it does
    for (int k = 0; k <= kLightMarchMaxSpans; ++k) {
        float s1Box = min(s1, exitNodes);
        vec3 span = vec3(0.0);
        if (s1Box > s0) {
            // A span of a whole node is 1 node only up to float rounding of s0 and s1: the tolerance
            // keeps its count of segments from flipping (and the float64 oracle in step).
            int count = max(1, int(ceil((s1Box - s0) * stepsPerNode - 1e-3)));
            float ds = (s1Box - s0) / float(count);
            // (A cache of the cell's corners, as light_depth.comp keeps, saved nothing here on
            // llvmpipe: 1015 against 998 ms a 128³ frame.)
            for (int i = 0; i < count; ++i) span += sampleGrid(s_extinction, stencilAt(p + (s0 + (float(i) + 0.5) * ds) * toLight));
            span *= ds * worldPerNode;
        }
        tau += span;
        if (exitNodes <= s1 || min(tau.r, min(tau.g, tau.b)) >= kLightMarchOpaque) break;
        if (k == kLightMarchMaxSpans || (s1 >= kLightMarchMinNodes && max3(span) < kLightMarchDenseSpan)) {
            gridAt = s1;
            break;
        }
        s0 = s1;
        s1 += 1.0;
    }
    // On the node plane the grid is exact along the beam.
    if (gridAt >= 0.0) tau += max(lightDepthOnPlane(s_lightDepth[l], vec3(g.xy, g.z - gridAt), u.lightGridDims[l]), vec3(0.0));
    return tau;
}

#endif

#if VOLSTYLE_LIT
// L_scat(x, ω) = Σ_l p(ω_l·(−ω)) E_l T_l(x) + the lobes' share, at index-space point p
// (V_l = 1: no occluders).
vec3 inScattering(vec3 p, vec3 dir) {
    vec3 sum = vec3(0.0);
    // Unrolled by hand, so each light's texture is named by a constant: lightDepthAt's loops keep
    // compilers from unrolling a loop over the lights, and indexing the sampler array with its
    // counter made Mesa 22's llvmpipe read the background plate as black (two lights or more).
#define VOLSTYLE_LIGHT_TERM(l) \
    sum += phaseFunction(dot(u.lightDirection[l].xyz, -dir)) * u.lightIrradiance[l].rgb * exp(-lightDepthAt(l, p))
#if VOLSTYLE_NUM_LIGHTS > 0
    VOLSTYLE_LIGHT_TERM(0);
#endif
#if VOLSTYLE_NUM_LIGHTS > 1
    VOLSTYLE_LIGHT_TERM(1);
#endif
#if VOLSTYLE_NUM_LIGHTS > 2
    VOLSTYLE_LIGHT_TERM(2);
#endif
#if VOLSTYLE_NUM_LIGHTS > 3
    VOLSTYLE_LIGHT_TERM(3);
#endif
#undef VOLSTYLE_LIGHT_TERM
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

/* hole_noise.h — the Perlin noise of the GI paper's hole creation (Eq. 4–5), shared by C++ (the
 * threshold's calibration, the tests' references) and GLSL (shadow_holes.comp): scalar code only,
 * so that one source compiles as both and the CPU sees exactly the holes the GPU cuts.
 *
 *   perlin(x, y)    classic 2D gradient noise (Perlin 2002's quintic fade), 8 gradient directions
 *                   picked by an integer hash of the lattice point and the seed;
 *   fbm(x, y)       Σ_{i<o} pⁱ perlin(2ⁱ x, 2ⁱ y) / Σ pⁱ  (Eq. 5's octaves o and persistence p);
 *   holeNoise(x, y) the paper's two-step lookup for animation: w = fbm(q + τ), then fbm(q + k(w, −w)),
 *                   so holes change shape as time τ runs instead of sliding. */
#ifndef VOLSTYLE_HOLE_NOISE_H
#define VOLSTYLE_HOLE_NOISE_H

#ifndef VOLSTYLE_GLSL
#include <cmath>
#include <cstdint>
namespace volstyle::core::noise {
using uint = std::uint32_t;
using std::floor;
#define VS_NOISE_FN inline
#else
#define VS_NOISE_FN
#endif

VS_NOISE_FN uint noiseHash(uint x) {
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

/* The gradient of lattice point (ix, iy) dotted with the offset (dx, dy) from it. */
VS_NOISE_FN float gradientDot(int ix, int iy, uint seed, float dx, float dy) {
    uint k = noiseHash(uint(ix) * 0x8da6b343u ^ noiseHash(uint(iy) * 0xd8163841u ^ seed)) & 7u;
    const float r = 0.70710678f;
    float gx = k < 2u ? (k == 0u ? 1.0f : -1.0f) : (k < 4u ? 0.0f : ((k == 4u || k == 6u) ? r : -r));
    float gy = k < 2u ? 0.0f : (k < 4u ? (k == 2u ? 1.0f : -1.0f) : (k < 6u ? r : -r));
    return gx * dx + gy * dy;
}

VS_NOISE_FN float noiseFade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

VS_NOISE_FN float perlin(float x, float y, uint seed) {
    float x0 = floor(x), y0 = floor(y);
    int ix = int(x0), iy = int(y0);
    float fx = x - x0, fy = y - y0;
    float n00 = gradientDot(ix, iy, seed, fx, fy);
    float n10 = gradientDot(ix + 1, iy, seed, fx - 1.0f, fy);
    float n01 = gradientDot(ix, iy + 1, seed, fx, fy - 1.0f);
    float n11 = gradientDot(ix + 1, iy + 1, seed, fx - 1.0f, fy - 1.0f);
    float u = noiseFade(fx), v = noiseFade(fy);
    float a = n00 + u * (n10 - n00), b = n01 + u * (n11 - n01);
    return a + v * (b - a);
}

VS_NOISE_FN float fbm(float x, float y, int octaves, float persistence, uint seed) {
    float sum = 0.0f, norm = 0.0f, amplitude = 1.0f, scale = 1.0f;
    for (int i = 0; i < octaves; ++i) {
        sum += amplitude * perlin(x * scale, y * scale, seed + uint(i) * 0x632be5abu);
        norm += amplitude;
        amplitude *= persistence;
        scale *= 2.0f;
    }
    return sum / norm;
}

/* N at noise coordinates (x, y) for the time offset (ox, oy) (the paper's two-step lookup). */
VS_NOISE_FN float holeNoise(float x, float y, float ox, float oy, int octaves, float persistence, uint seed) {
    const float warp = 1.5f;
    float w = fbm(x + ox, y + oy, octaves, persistence, seed);
    return fbm(x + warp * w, y - warp * w, octaves, persistence, seed ^ 0x5bd1e995u);
}

#ifndef VOLSTYLE_GLSL
}  // namespace volstyle::core::noise
#endif
#undef VS_NOISE_FN
#endif

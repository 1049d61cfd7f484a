#include "core/volume/noise.h"

#include <cmath>
#include <random>

namespace volstyle::core {
namespace {

double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }
double lerp(double t, double a, double b) { return a + t * (b - a); }
double grad(int hash, double x, double y, double z) {
    int h = hash & 15;
    double u = h < 8 ? x : y;
    double v = h < 4 ? y : (h == 12 || h == 14 ? x : z);
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

}  // namespace

PerlinNoise::PerlinNoise(uint32_t seed) {
    std::array<uint8_t, 256> p;
    for (int i = 0; i < 256; ++i) p[i] = uint8_t(i);
    // Fisher–Yates with raw mt19937 outputs (std distributions are not portable).
    std::mt19937 rng(seed);
    for (int i = 255; i > 0; --i) std::swap(p[i], p[rng() % uint32_t(i + 1)]);
    for (int i = 0; i < 512; ++i) m_perm[i] = p[i & 255];
}

double PerlinNoise::operator()(const Vec3d& q) const {
    double fx = std::floor(q.x), fy = std::floor(q.y), fz = std::floor(q.z);
    int X = int(fx) & 255, Y = int(fy) & 255, Z = int(fz) & 255;
    double x = q.x - fx, y = q.y - fy, z = q.z - fz;
    double u = fade(x), v = fade(y), w = fade(z);
    const auto& P = m_perm;
    int A = P[X] + Y, AA = P[A] + Z, AB = P[A + 1] + Z;
    int B = P[X + 1] + Y, BA = P[B] + Z, BB = P[B + 1] + Z;
    return lerp(w,
                lerp(v, lerp(u, grad(P[AA], x, y, z), grad(P[BA], x - 1, y, z)),
                     lerp(u, grad(P[AB], x, y - 1, z), grad(P[BB], x - 1, y - 1, z))),
                lerp(v, lerp(u, grad(P[AA + 1], x, y, z - 1), grad(P[BA + 1], x - 1, y, z - 1)),
                     lerp(u, grad(P[AB + 1], x, y - 1, z - 1), grad(P[BB + 1], x - 1, y - 1, z - 1))));
}

double PerlinNoise::fbm(const Vec3d& p, int octaves, double lacunarity, double gain) const {
    double sum = 0, amp = 1, norm = 0, freq = 1;
    for (int o = 0; o < octaves; ++o) {
        sum += amp * (*this)(p * freq);
        norm += amp;
        amp *= gain;
        freq *= lacunarity;
    }
    return sum / norm;
}

Vec3d PerlinNoise::fbm3(const Vec3d& p, int octaves) const {
    return {fbm(p, octaves), fbm(p + Vec3d(31.4, 17.7, 5.3), octaves),
            fbm(p + Vec3d(-11.2, 43.1, 27.9), octaves)};
}

}  // namespace volstyle::core

#include "core/stylize/shadow_edits.h"

#include <algorithm>
#include <cmath>

#include "core/base/errors.h"
#include "core/shaders/hole_noise.h"

namespace volstyle::core {

std::vector<float> epipolarDilationReference(const std::vector<float>& depth, int n, const Epipole& e, int kernelTexels) {
    VOLSTYLE_CHECK(depth.size(), ==, size_t(n) * n);
    std::vector<float> out(depth.size());
    const float lx = float(e.x), ly = float(e.y), zl = float(e.depth), sense = float(e.sense);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            float best = depth[size_t(y) * n + x];
            const float px = float(x) + 0.5f, py = float(y) + 0.5f;
            const float dist = std::hypot(px - lx, py - ly);
            if (dist > 1e-3f) {
                const float dx = (lx - px) / dist * sense, dy = (ly - py) / dist * sense;
                const int kernel = sense > 0 ? std::min(kernelTexels, int(dist)) : kernelTexels;
                for (int k = 1; k <= kernel; ++k) {
                    const float sx = px + float(k) * dx, sy = py + float(k) * dy;
                    const int ix = int(std::floor(sx)), iy = int(std::floor(sy));
                    if (ix < 0 || iy < 0 || ix >= n || iy >= n) break;
                    const float zs = depth[size_t(iy) * n + ix];
                    if (zs >= 1.0f) continue;
                    const float ds = std::max(std::hypot(sx - lx, sy - ly), 1e-3f);
                    best = std::min(best, std::clamp(dist / ds * (zs - zl) + zl, 0.0f, 1.0f));
                }
            }
            out[size_t(y) * n + x] = best;
        }
    return out;
}

float holeThreshold(double probability, int octaves, double persistence, uint32_t seed) {
    if (probability <= 0) return -1e30f;
    if (probability >= 1) return 1e30f;
    constexpr int kSide = 256;  // samples a side, a quarter of a noise unit apart (plus a jitter)
    std::vector<float> values;
    values.reserve(size_t(kSide) * kSide);
    for (int j = 0; j < kSide; ++j)
        for (int i = 0; i < kSide; ++i) {
            const uint32_t h = noise::noiseHash(uint32_t(j * kSide + i) ^ 0xa511e9b3u);
            const float x = 0.25f * (float(i) + float(h & 0xffffu) / 65536.0f);
            const float y = 0.25f * (float(j) + float(h >> 16) / 65536.0f);
            values.push_back(noise::holeNoise(x, y, 0.0f, 0.0f, octaves, float(persistence), seed));
        }
    const size_t k = std::min(values.size() - 1, size_t(probability * double(values.size())));
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(k), values.end());
    return values[k];
}

void holeTimeOffset(double time, double speed, double& ox, double& oy) {
    const double tau = speed * time;
    ox = tau;
    oy = 0.61803398875 * tau;
}

bool isHole(const HoleMap& h, int x, int y) {
    const float qx = float(h.originX) + (float(x) + 0.5f) * float(h.stepX);
    const float qy = float(h.originY) + (float(y) + 0.5f) * float(h.stepY);
    return noise::holeNoise(qx, qy, float(h.offsetX), float(h.offsetY), h.octaves, float(h.persistence), h.seed) < h.threshold;
}

std::vector<float> holesReference(const std::vector<float>& depth, int n, const HoleMap& h) {
    VOLSTYLE_CHECK(depth.size(), ==, size_t(n) * n);
    std::vector<float> out = depth;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (out[size_t(y) * n + x] < 1.0f && isHole(h, x, y)) out[size_t(y) * n + x] = 1.0f;
    return out;
}

}  // namespace volstyle::core

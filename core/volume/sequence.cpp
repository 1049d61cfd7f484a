#include "core/volume/sequence.h"

#include <algorithm>
#include <cmath>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

size_t at(Int3 n, int i, int j, int k) { return (size_t(k) * size_t(n.y) + size_t(j)) * size_t(n.x) + size_t(i); }

/// Trilinear lookup of RGB `grid` at index point p, clamped to the edge.
Vec3d sample(const std::vector<float>& grid, Int3 n, const Vec3d& p) {
    int i0[3], i1[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
        const double q = std::clamp(p[a], 0.0, double(n[a] - 1));
        i0[a] = std::min(int(q), n[a] - 1), i1[a] = std::min(i0[a] + 1, n[a] - 1), f[a] = q - i0[a];
    }
    Vec3d r(0, 0, 0);
    for (int c = 0; c < 8; ++c) {
        const int x = c & 1 ? i1[0] : i0[0], y = c & 2 ? i1[1] : i0[1], z = c & 4 ? i1[2] : i0[2];
        const double w = (c & 1 ? f[0] : 1 - f[0]) * (c & 2 ? f[1] : 1 - f[1]) * (c & 4 ? f[2] : 1 - f[2]);
        const size_t e = 3 * at(n, x, y, z);
        r += Vec3d(grid[e], grid[e + 1], grid[e + 2]) * w;
    }
    return r;
}

}  // namespace

std::vector<float> velocityInIndexUnits(const std::vector<float>& v, const Mat4& indexFromWorld) {
    std::vector<float> out(v.size());
    for (size_t i = 0; i + 2 < v.size(); i += 3) {
        const Vec3d d = indexFromWorld.applyVector(Vec3d(v[i], v[i + 1], v[i + 2]));
        out[i] = float(d.x), out[i + 1] = float(d.y), out[i + 2] = float(d.z);
    }
    return out;
}

std::vector<float> advect(const std::vector<float>& grid, Int3 n, const std::vector<float>& velocity, double frames) {
    if (grid.size() != 3 * size_t(n.volume())) throw InvalidArgument("advect: the grid does not match its dims");
    if (velocity.empty() || frames == 0) return grid;
    if (velocity.size() != grid.size()) throw InvalidArgument("advect: the velocity grid does not match the grid");
    std::vector<float> out(grid.size());
    for (int k = 0; k < n.z; ++k)
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
                const size_t e = 3 * at(n, i, j, k);
                const Vec3d back = Vec3d(i, j, k) - Vec3d(velocity[e], velocity[e + 1], velocity[e + 2]) * frames;
                const Vec3d v = sample(grid, n, back);
                out[e] = float(v.x), out[e + 1] = float(v.y), out[e + 2] = float(v.z);
            }
    return out;
}

std::vector<float> blend(const std::vector<float>& a, const std::vector<float>& b, double w) {
    if (a.size() != b.size()) throw InvalidArgument("blend: the grids differ in size");
    std::vector<float> out(a.size());
    for (size_t i = 0; i < a.size(); ++i) out[i] = float((1 - w) * a[i] + w * b[i]);
    return out;
}

void extendByDiffusion(std::vector<float>& grid, Int3 n, const std::vector<uint8_t>& known, int maxSweeps, double tolerance) {
    if (known.size() != size_t(n.volume()) || grid.size() != 3 * known.size()) throw InvalidArgument("extendByDiffusion: sizes disagree");
    if (std::none_of(known.begin(), known.end(), [](uint8_t k) { return k != 0; })) return;
    std::vector<size_t> free;
    for (size_t v = 0; v < known.size(); ++v)
        if (!known[v]) free.push_back(v);
    if (free.empty()) return;
    // Start the free voxels at the known ones' mean: fewer sweeps than from zero.
    Vec3d mean(0, 0, 0);
    double count = 0;
    for (size_t v = 0; v < known.size(); ++v)
        if (known[v]) mean += Vec3d(grid[3 * v], grid[3 * v + 1], grid[3 * v + 2]), count += 1;
    mean = mean * (1 / count);
    for (size_t v : free) grid[3 * v] = float(mean.x), grid[3 * v + 1] = float(mean.y), grid[3 * v + 2] = float(mean.z);
    std::vector<float> next = grid;
    for (int sweep = 0; sweep < maxSweeps; ++sweep) {
        double moved = 0;
        for (size_t v : free) {
            const int i = int(v % size_t(n.x)), j = int(v / size_t(n.x) % size_t(n.y)), k = int(v / (size_t(n.x) * size_t(n.y)));
            Vec3d sum(0, 0, 0);
            int neighbours = 0;
            const int offsets[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
            for (const auto& o : offsets) {
                const int a = i + o[0], b = j + o[1], c = k + o[2];
                if (a < 0 || b < 0 || c < 0 || a >= n.x || b >= n.y || c >= n.z) continue;  // zero-flux border
                const size_t e = 3 * at(n, a, b, c);
                sum += Vec3d(grid[e], grid[e + 1], grid[e + 2]);
                ++neighbours;
            }
            const Vec3d value = sum * (1.0 / std::max(neighbours, 1));
            for (int ch = 0; ch < 3; ++ch) {
                moved = std::max(moved, std::abs(value[ch] - grid[3 * v + size_t(ch)]));
                next[3 * v + size_t(ch)] = float(value[ch]);
            }
        }
        for (size_t v : free)
            for (int ch = 0; ch < 3; ++ch) grid[3 * v + size_t(ch)] = next[3 * v + size_t(ch)];
        if (moved <= tolerance) break;
    }
}

}  // namespace volstyle::core

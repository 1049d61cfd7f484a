#include "core/volume/sequence.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <thread>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

/// Trilinear lookup of RGB `grid` at index point p, clamped to the edge.
Vec3d sample(const std::vector<float>& grid, const GridSpace& space, const Vec3d& p) {
    const Int3 n = space.dims();
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
        const size_t e = 3 * space.at({x, y, z});
        r += Vec3d(grid[e], grid[e + 1], grid[e + 2]) * w;
    }
    return r;
}

/// A voxel to extend: where it is stored and where its 6-neighbours are (−x, +x, −y, +y, −z, +z;
/// kNone where the box or the active region ends: zero flux).
struct FreeVoxel {
    static constexpr uint32_t kNone = UINT32_MAX;
    uint32_t stored;
    std::array<uint32_t, 6> neighbours;
};

std::vector<FreeVoxel> freeVoxels(const GridSpace& space, const std::vector<uint8_t>& known) {
    if (space.storedVoxels() >= FreeVoxel::kNone)
        throw LimitExceeded("a grid of over 4 G voxels is too large to extend into its empty voxels");
    const Int3 n = space.dims();
    size_t count = 0;
    space.forEachVoxel([&](Int3, size_t stored) { count += known[stored] ? 0 : 1; });
    std::vector<FreeVoxel> free;
    free.reserve(count);
    space.forEachVoxel([&](Int3 v, size_t stored) {
        if (known[stored]) return;
        FreeVoxel f{uint32_t(stored), {}};
        const int offsets[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
        for (int o = 0; o < 6; ++o) {
            const Int3 q{v.x + offsets[o][0], v.y + offsets[o][1], v.z + offsets[o][2]};
            const bool inside = q.x >= 0 && q.y >= 0 && q.z >= 0 && q.x < n.x && q.y < n.y && q.z < n.z && space.holds(q);
            f.neighbours[size_t(o)] = inside ? uint32_t(space.at(q)) : FreeVoxel::kNone;
        }
        free.push_back(f);
    });
    return free;
}

/// Calls f(begin, end) over [0, count) split among the cores (a core per 32 K items at most: a
/// thread costs tens of microseconds), and waits.
template <typename F>
void inParallel(size_t count, F&& f) {
    const size_t workers = std::clamp<size_t>(std::min<size_t>(std::thread::hardware_concurrency(), count >> 15), 1, 16);
    const size_t chunk = (count + workers - 1) / workers;
    std::vector<std::thread> threads;
    for (size_t w = 1; w < workers && w * chunk < count; ++w) threads.emplace_back([&, w] { f(w * chunk, std::min(count, (w + 1) * chunk)); });
    f(0, std::min(count, chunk));
    for (auto& t : threads) t.join();
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

std::vector<float> advect(const std::vector<float>& grid, const GridSpace& space, const std::vector<float>& velocity, double frames) {
    if (grid.size() != 3 * space.storedVoxels()) throw InvalidArgument("advect: the grid does not match its voxels");
    if (space.hasSharedSlots()) throw InvalidArgument("advect: a tile's bricks share their voxels (unshare them first)");
    if (velocity.empty() || frames == 0) return grid;
    if (velocity.size() != grid.size()) throw InvalidArgument("advect: the velocity grid does not match the grid");
    std::vector<float> out = grid;  // the background (sparse) stays as it is
    space.forEachVoxel([&](Int3 p, size_t stored) {
        const size_t e = 3 * stored;
        const Vec3d back = Vec3d(p.x, p.y, p.z) - Vec3d(velocity[e], velocity[e + 1], velocity[e + 2]) * frames;
        const Vec3d v = sample(grid, space, back);
        out[e] = float(v.x), out[e + 1] = float(v.y), out[e + 2] = float(v.z);
    });
    return out;
}

std::vector<float> blend(const std::vector<float>& a, const std::vector<float>& b, double w) {
    if (a.size() != b.size()) throw InvalidArgument("blend: the grids differ in size");
    std::vector<float> out(a.size());
    for (size_t i = 0; i < a.size(); ++i) out[i] = float((1 - w) * a[i] + w * b[i]);
    return out;
}

void extendByDiffusion(std::vector<float>& grid, const GridSpace& space, const std::vector<uint8_t>& known, int maxSweeps,
                       double tolerance) {
    if (known.size() != space.storedVoxels() || grid.size() != 3 * known.size()) throw InvalidArgument("extendByDiffusion: sizes disagree");
    if (space.hasSharedSlots()) throw InvalidArgument("extendByDiffusion: a tile's bricks share their voxels (unshare them first)");
    if (std::none_of(known.begin(), known.end(), [](uint8_t k) { return k != 0; })) return;
    const std::vector<FreeVoxel> free = freeVoxels(space, known);
    if (free.empty()) return;
    // Start the free voxels at the known ones' mean: fewer sweeps than from zero.
    Vec3d mean(0, 0, 0);
    double count = 0;
    for (size_t v = 0; v < known.size(); ++v)
        if (known[v]) mean += Vec3d(grid[3 * v], grid[3 * v + 1], grid[3 * v + 2]), count += 1;
    mean = mean * (1 / count);
    for (const FreeVoxel& f : free) grid[3 * size_t(f.stored)] = float(mean.x), grid[3 * size_t(f.stored) + 1] = float(mean.y), grid[3 * size_t(f.stored) + 2] = float(mean.z);
    // Jacobi sweeps, split among the cores (each voxel's new value reads only the last sweep's).
    std::vector<float> next(3 * free.size());
    std::mutex mutex;
    for (int sweep = 0; sweep < maxSweeps; ++sweep) {
        double moved = 0;
        inParallel(free.size(), [&](size_t begin, size_t end) {
            double movedHere = 0;
            for (size_t i = begin; i < end; ++i) {
                Vec3d sum(0, 0, 0);
                int neighbours = 0;
                for (uint32_t q : free[i].neighbours)
                    if (q != FreeVoxel::kNone) sum += Vec3d(grid[3 * size_t(q)], grid[3 * size_t(q) + 1], grid[3 * size_t(q) + 2]), ++neighbours;
                const Vec3d value = sum * (1.0 / std::max(neighbours, 1));
                for (int ch = 0; ch < 3; ++ch) {
                    movedHere = std::max(movedHere, std::abs(value[ch] - grid[3 * size_t(free[i].stored) + size_t(ch)]));
                    next[3 * i + size_t(ch)] = float(value[ch]);
                }
            }
            std::lock_guard lock(mutex);
            moved = std::max(moved, movedHere);
        });
        inParallel(free.size(), [&](size_t begin, size_t end) {
            for (size_t i = begin; i < end; ++i) std::copy_n(&next[3 * i], 3, &grid[3 * size_t(free[i].stored)]);
        });
        if (moved <= tolerance) break;
    }
}

}  // namespace volstyle::core

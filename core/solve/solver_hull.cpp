// The solver's hull (TVCG Sec. 5.2): the unknowns that can matter — those whose support touches
// non-zero extinction, or for an extinction solve those the targets' masks do not carve away
// (each masked pixel that sees empty space empties the cells along its ray).
#include <algorithm>

#include "core/solve/solver_state.h"

namespace volstyle::core {
namespace {

/// A masked pixel whose observation is below this everywhere sees empty space (carves the hull).
constexpr float kEmptyObservation = 1e-6f;

}  // namespace

void Solver::State::buildHull() {
    hullHost.assign(elements * 4, 0.0f);
    if (!opt.useHull) {
        for (size_t e = 0; e < elements; ++e) hullHost[4 * e] = hullHost[4 * e + 1] = hullHost[4 * e + 2] = 1.0f;
    } else if (opt.unknown != Unknown::Extinction) {
        markHullFromExtinction();
    } else {
        markHullFromMasks(obsHost, sqrtWHost);
    }
    hull.upload(hullHost);
    movable.upload(hullHost);
    size_t count = 0;
    for (size_t e = 0; e < elements; ++e) count += hullHost[4 * e] > 0 ? 1 : 0;
    report.unknownCount = elements;
    report.hullCount = count;
}

namespace {

/// Marks unknown (i, j, k) in every block.
void markCell(std::vector<float>& hull, size_t cells, size_t blocks, Int3 udims, int i, int j, int k) {
    for (size_t b = 0; b < blocks; ++b) {
        size_t e = b * cells + (size_t(k) * udims.y + size_t(j)) * udims.x + size_t(i);
        hull[4 * e] = hull[4 * e + 1] = hull[4 * e + 2] = 1.0f;
    }
}

}  // namespace

void Solver::State::markHullFromExtinction() {
    // Unknowns whose basis support overlaps non-zero extinction (TVCG Sec. 5.2, visual hulls): the
    // rest have no influence on any pixel.
    const Int3 n = volume.dims();
    const Vec3d scale(double(udims.x) / n.x, double(udims.y) / n.y, double(udims.z) / n.z);
    const size_t blocks = elements / cells;
    // Marks the unknowns whose support holds voxel (i, j, k)'s neighbourhood.
    auto markAround = [&](int i, int j, int k) {
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            int v = a == 0 ? i : (a == 1 ? j : k);
            double qlo = (v - 1 + 0.5) * scale[a] - 0.5, qhi = (v + 1 + 0.5) * scale[a] - 0.5;
            lo[a] = std::clamp(int(std::floor(qlo)), 0, udims[a] - 1);
            hi[a] = std::clamp(int(std::ceil(qhi)), 0, udims[a] - 1);
        }
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x) {
                    if (!volume.isSparse()) {
                        markCell(hullHost, cells, blocks, udims, x, y, z);
                        continue;
                    }
                    const size_t cell = unknownBricks.storageIndex({x, y, z});
                    if (cell < size_t(kBrickVoxels)) continue;  // the background brick: not an unknown
                    for (size_t b = 0; b < blocks; ++b) std::fill_n(&hullHost[4 * (b * cells + cell)], 3, 1.0f);
                }
    };
    if (volume.isSparse()) {  // the medium is in the active bricks
        const std::vector<float>& ext = volume.extinction();
        forEachActiveVoxel(volume, [&](Int3 p, size_t s) {
            if (std::max({ext[3 * s], ext[3 * s + 1], ext[3 * s + 2]}) > 0) markAround(p.x, p.y, p.z);
        });
        return;
    }
    for (int k = 0; k < n.z; ++k)
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i)
                if (maxComponent(volume.extinctionAt(i, j, k)) > 0) markAround(i, j, k);
}

void Solver::State::markHullFromMasks(const std::vector<float>& o, const std::vector<float>& w) {
    // Extinction: carve with the targets' masks. An unknown whose centre a view sees through a
    // constrained pixel that shows only background (o = 0) is outside the hull.
    const Int3 n = volume.dims();
    const Vec3d scale(double(udims.x) / n.x, double(udims.y) / n.y, double(udims.z) / n.z);
    auto carved = [&](const Vec3d& pw) {
        size_t offset = 0;
        for (const auto& v : views) {
            if (auto px = v.camera.project(pw)) {
                size_t idx = 4 * (offset + size_t(px->y) * v.camera.width + size_t(px->x));
                bool constrained = w[idx] > 0 || w[idx + 1] > 0 || w[idx + 2] > 0;
                bool empty = o[idx] <= kEmptyObservation && o[idx + 1] <= kEmptyObservation && o[idx + 2] <= kEmptyObservation;
                if (constrained && empty) return true;
            }
            offset += size_t(v.camera.width) * v.camera.height;
        }
        return false;
    };
    if (volume.isSparse()) {  // the unknowns are the stored voxels of their bricks
        unknownBricks.forEachStoredVoxel([&](Int3 c, size_t cell) {
            if (!carved(volume.worldFromIndex().applyPoint((Vec3d(c.x, c.y, c.z) + Vec3d(0.5)) / scale - Vec3d(0.5))))
                std::fill_n(&hullHost[4 * cell], 3, 1.0f);
        });
        return;
    }
    for (int k = 0; k < udims.z; ++k)
        for (int j = 0; j < udims.y; ++j)
            for (int i = 0; i < udims.x; ++i) {
                const Vec3d pw = volume.worldFromIndex().applyPoint((Vec3d(i, j, k) + Vec3d(0.5)) / scale - Vec3d(0.5));
                const bool inside = !carved(pw);
                if (inside) markCell(hullHost, cells, elements / cells, udims, i, j, k);
            }
}

}  // namespace volstyle::core

// The solver on sparse volumes (issue #39): the unknowns are the stored voxels of a sparse grid —
// the volume's own bricks (and an apron where the unknowns can reach), or coarser bricks over the
// same region when a resolution is asked for or the finest would not fit the GPU's storage blocks.
// W/Wᵀ index them through that grid's brick table (project.comp), the Laplacian finds neighbours
// through it (vector_ops.comp), and the result is written into the volume's bricks.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/base/errors.h"
#include "core/solve/solver_state.h"
#include "core/volume/resample.h"

namespace volstyle::core {
namespace {

/// The bricks of a grid of `coarse` cells over the same box as `fine`'s that hold every unknown a
/// sample in an active fine brick reaches (both trilinear corners along each axis).
BrickLayout coarseBricks(const BrickLayout& fine, Int3 coarse) {
    BrickLayout out(coarse, {0, 0, 0});
    const Int3 n = fine.dims();
    const Vec3d scale(double(coarse.x) / n.x, double(coarse.y) / n.y, double(coarse.z) / n.z);
    for (size_t slot = 1; slot < fine.slots(); ++slot) {
        const Int3 f = fine.firstVoxel(fine.brickOfSlot(slot));
        Int3 lo, hi;
        for (int a = 0; a < 3; ++a) {
            const int v0 = std::max(f[a], 0), v1 = std::min(f[a] + kBrickSide - 1, n[a] - 1);
            const int c0 = std::clamp(int(std::floor((v0 + 0.5) * scale[a] - 0.5)), 0, coarse[a] - 1);
            const int c1 = std::clamp(int(std::floor((v1 + 0.5) * scale[a] - 0.5)) + 1, 0, coarse[a] - 1);
            (a == 0 ? lo.x : a == 1 ? lo.y : lo.z) = c0;
            (a == 0 ? hi.x : a == 1 ? hi.y : hi.z) = c1;
        }
        const Int3 b0 = out.brickOf(lo), b1 = out.brickOf(hi);
        for (int z = b0.z; z <= b1.z; ++z)
            for (int y = b0.y; y <= b1.y; ++y)
                for (int x = b0.x; x <= b1.x; ++x) out.activate({x, y, z});
    }
    return out;
}

Int3 halved(Int3 d) { return {std::max(1, (d.x + 1) / 2), std::max(1, (d.y + 1) / 2), std::max(1, (d.z + 1) / 2)}; }

}  // namespace

std::vector<Int3> sparseSolveApron(const Volume& volume, Unknown unknown) {
    const BrickLayout* bricks = volume.bricks();
    if (!bricks) return {};
    std::vector<uint8_t> added(bricks->slotTable().size(), 0);
    std::vector<Int3> more;
    auto add = [&](Int3 b) {
        if (bricks->isActive(b) || added[bricks->brickIndex(b)]) return;
        added[bricks->brickIndex(b)] = 1;
        more.push_back(b);
    };
    if (unknown == Unknown::Extinction) {  // the medium can grow anywhere next to it
        bricks->forEachActiveBrick([&](Int3 b, uint32_t) { bricks->forEachBrickAround(b, 1, add); });
        return more;
    }
    // Emission and albedo: the hull is the medium and a voxel around it (solver_hull.cpp):
    // only voxels on a brick's faces reach into another brick.
    const Int3 n = volume.dims(), o = bricks->offset();
    const std::vector<float>& ext = volume.extinction();
    forEachActiveVoxel(volume, [&](Int3 p, size_t s) {
        if (std::max({ext[3 * s], ext[3 * s + 1], ext[3 * s + 2]}) <= 0) return;
        const Int3 l{(p.x + o.x) % kBrickSide, (p.y + o.y) % kBrickSide, (p.z + o.z) % kBrickSide};
        const auto inner = [](int v) { return v > 0 && v < kBrickSide - 1; };
        if (inner(l.x) && inner(l.y) && inner(l.z)) return;
        for (int z = std::max(p.z - 1, 0); z <= std::min(p.z + 1, n.z - 1); ++z)
            for (int y = std::max(p.y - 1, 0); y <= std::min(p.y + 1, n.y - 1); ++y)
                for (int x = std::max(p.x - 1, 0); x <= std::min(p.x + 1, n.x - 1); ++x) add(bricks->brickOf({x, y, z}));
    });
    return more;
}

void Solver::State::growApron() {
    const std::vector<Int3> apron = sparseSolveApron(volume, opt.unknown);
    volume.unshareTiles();  // every unknown a voxel of its own
    for (const Int3& b : apron) volume.activateBrick(b);
}

void Solver::State::chooseSparseUnknowns() {
    const Int3 n = volume.dims();
    if (udims.x > n.x || udims.y > n.y || udims.z > n.z)
        throw InvalidArgument("a sparse volume is solved at its own resolution or coarser, not finer");
    const BrickLayout& fine = *volume.bricks();
    unknownBricks = udims == n ? fine : coarseBricks(fine, udims);
    if (opt.resolution) return;
    // No resolution asked for: the finest grid whose vectors fit one storage block (llvmpipe:
    // 128 MiB, 8 M unknowns; a GPU's are larger), halving the resolution until they do.
    const size_t blocks = opt.unknown == Unknown::EmissionAlbedo ? 2 : 1;
    const double limit = double(device.capabilities().maxStorageBlockBytes);
    while (double(unknownBricks.storedVoxels() * blocks) * 16 > limit && (udims.x > 1 || udims.y > 1 || udims.z > 1)) {
        udims = halved(udims);
        unknownBricks = coarseBricks(fine, udims);
    }
    if (!(udims == n))
        spdlog::info("solve: {} sparse unknowns at {}x{}x{} ({} per side of the volume's), so that a vector fits this GPU's storage blocks",
                     unknownBricks.storedVoxels() * blocks, udims.x, udims.y, udims.z, double(n.x) / udims.x);
}

void Solver::State::sparseUnknownsFrom(const std::vector<float>& grid, std::vector<float>& init, size_t block) const {
    const Int3 n = volume.dims();
    if (udims == n) {  // the unknowns are the stored voxels themselves
        for (size_t c = 0; c < cells; ++c) std::copy_n(&grid[3 * c], 3, &init[4 * (block * cells + c)]);
        return;
    }
    // The volume at each unknown's centre (trilinear between the volume's voxels).
    const Vec3d scale(double(udims.x) / n.x, double(udims.y) / n.y, double(udims.z) / n.z);
    unknownBricks.forEachStoredVoxel([&](Int3 c, size_t cell) {
        const Vec3d q((c.x + 0.5) / scale.x - 0.5, (c.y + 0.5) / scale.y - 0.5, (c.z + 0.5) / scale.z - 0.5);
        const Vec3d v = sampleGrid(GridView{grid, n, 3, 0, volume.bricks()}, q, BasisType::Trilinear);
        for (int ch = 0; ch < 3; ++ch) init[4 * (block * cells + cell) + size_t(ch)] = float(v[ch]);
    });
}

std::vector<float> Solver::State::sparseGridFrom(const std::vector<float>& unknowns, size_t block) const {
    const Int3 n = volume.dims();
    std::vector<float> grid(3 * volume.storedVoxels(), 0.0f);
    if (udims == n) {
        for (size_t c = 0; c < cells; ++c) std::copy_n(&unknowns[4 * (block * cells + c)], 3, &grid[3 * c]);
        return grid;
    }
    // Coarser unknowns: the basis functions evaluated at every stored voxel (trilinear, or the
    // box's nearest unknown), as the projector weighs them. The background brick keeps the
    // property's background (albedo 1: what inactive bricks read).
    const bool albedo = opt.unknown == Unknown::Albedo || (opt.unknown == Unknown::EmissionAlbedo && block == 1);
    const std::vector<float>& was = albedo ? volume.albedo() : opt.unknown == Unknown::Extinction ? volume.extinction() : volume.emission();
    if (was.size() == grid.size()) std::copy_n(was.begin(), 3 * kBrickVoxels, grid.begin());
    else if (albedo) std::fill_n(grid.begin(), 3 * kBrickVoxels, kDefaultAlbedo);
    const Vec3d scale(double(udims.x) / n.x, double(udims.y) / n.y, double(udims.z) / n.z);
    const GridView from{unknowns, udims, 4, 4 * block * cells, &unknownBricks};
    forEachActiveVoxel(volume, [&](Int3 p, size_t s) {
        const Vec3d q((p.x + 0.5) * scale.x - 0.5, (p.y + 0.5) * scale.y - 0.5, (p.z + 0.5) * scale.z - 0.5);
        const Vec3d v = sampleGrid(from, q, opt.basis);
        for (int ch = 0; ch < 3; ++ch) grid[3 * s + size_t(ch)] = float(v[ch]);
    });
    return grid;
}

std::vector<float> Solver::State::priorOnUnknowns() const {
    const std::vector<float>& p = *opt.prior.values;
    if (p.size() == 3 * elements) return p;
    const size_t blocks = elements / cells;
    if (!volume.isSparse() || p.size() != 3 * blocks * volume.storedVoxels())
        throw InvalidArgument("the prior has " + std::to_string(p.size() / 3) + " values for " + std::to_string(elements) + " unknowns");
    // Per stored voxel of a sparse volume whose unknowns were coarsened to fit (key frames).
    std::vector<float> init(4 * elements), out(3 * elements);
    for (size_t b = 0; b < blocks; ++b) {
        const auto first = p.begin() + ptrdiff_t(3 * b * volume.storedVoxels());
        sparseUnknownsFrom(std::vector<float>(first, first + ptrdiff_t(3 * volume.storedVoxels())), init, b);
    }
    for (size_t e = 0; e < elements; ++e) std::copy_n(&init[4 * e], 3, &out[3 * e]);
    return out;
}

void Solver::State::checkVectorsFit() const {
    size_t pixels = 0;
    for (const auto& v : views) pixels += size_t(v.camera.width) * size_t(v.camera.height);
    const double limit = double(device.capabilities().maxStorageBlockBytes);
    const double unknownBytes = double(elements) * 16, pixelBytes = double(pixels) * 16;
    if (unknownBytes <= limit && pixelBytes <= limit) return;
    const bool unknownsOver = unknownBytes > limit;
    throw LimitExceeded(fmt::format(
        "the solve needs vectors of {} {} ({:.0f} MiB each), over the {:.0f} MiB this GPU's storage blocks hold; {}",
        unknownsOver ? elements : pixels, unknownsOver ? "unknowns" : "pixels", (unknownsOver ? unknownBytes : pixelBytes) / (1 << 20),
        limit / (1 << 20), unknownsOver ? "solve at a coarser resolution" : "use smaller or fewer views"));
}

}  // namespace volstyle::core

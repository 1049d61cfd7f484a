// Re-solve after a stroke (issue #12 item 3; SolveOptions::localResolve). The last solve left a
// volume that fits its targets; a stroke changes the targets of a few pixels. The change of the
// objective's gradient, Aᵀ(√w ⊙ Δo), is non-zero only on the unknowns those pixels' rays cross,
// so the re-solve moves exactly those (block coordinate descent on the block the stroke pulls
// at) and leaves the rest of the volume where the artist last saw it. Only the pixels that see a
// moving unknown can change, so W, Wᵀ and every vector operation run over them alone (the
// vectors' supports, gpu_vector.h); everything left out adds a constant to the objective, which
// is measured once here so that the objective and the views' RMS stay those of the whole problem.
#include <spdlog/spdlog.h>

#include <algorithm>

#include "core/solve/solve_cache.h"
#include "core/solve/solver_state.h"
#include "core/solve/sparse_rows.h"

namespace volstyle::core {
namespace {

/// Past this fraction of the constrained pixels changed, the stroke is not local: solve it all.
constexpr double kMaxChangedFraction = 0.25;

bool anyPositive(const float* v) { return v[0] > 0 || v[1] > 0 || v[2] > 0; }

bool differs(const float* x, const float* y) { return x[0] != y[0] || x[1] != y[1] || x[2] != y[2]; }

/// `elements` with their 6-neighbours (same block of `cells`) that are in the hull, ascending.
std::vector<uint32_t> withNeighbours(const std::vector<uint32_t>& elements, const std::vector<float>& hull, Int3 dims,
                                     size_t cells) {
    std::vector<uint8_t> in(hull.size() / 4, 0);
    for (uint32_t e : elements) {
        in[e] = 1;
        const size_t block = e / cells, cell = e % cells;
        const int i = int(cell % size_t(dims.x)), j = int(cell / size_t(dims.x) % size_t(dims.y)),
                  k = int(cell / (size_t(dims.x) * size_t(dims.y)));
        const int n[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
        for (const auto& q : n) {
            if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= dims.x || q[1] >= dims.y || q[2] >= dims.z) continue;
            const size_t f = block * cells + (size_t(q[2]) * size_t(dims.y) + size_t(q[1])) * size_t(dims.x) + size_t(q[0]);
            if (hull[4 * f] > 0) in[f] = 1;
        }
    }
    std::vector<uint32_t> out;
    for (size_t e = 0; e < in.size(); ++e)
        if (in[e]) out.push_back(uint32_t(e));
    return out;
}

}  // namespace

void Solver::State::restrictToStroke() {
    if (!cache) return;
    lastKey = lastSolveKey(volume, lighting, opt, udims, views);
    // The marks below read every view's rows; and the unknowns must be the volume's own grid: a
    // coarser one is resampled on the way in and out (a blur), so the rest would not stay put.
    if (!opt.localResolve || opt.prior.weight > 0 || !W->allCached() || !(udims == volume.dims()) || volume.isSparse()) return;
    const auto last = cache->findLastSolve(lastKey);
    if (!last || last->observations.size() != obsHost.size() || last->resultHash != unknownsHash(volume, opt.unknown))
        return;  // not the volume the last solve over these views left

    // The pixels whose observation or weight changed. One whose paint was erased has no row any
    // more to say what it saw: then the whole problem is solved again.
    std::vector<uint32_t> changed;
    for (size_t i = 0; i < W->pixelCount(); ++i) {
        const size_t q = 4 * i;
        const bool weighted = anyPositive(&rawWeightHost[q]);
        if (!differs(&rawWeightHost[q], &last->weights[q]) && !(weighted && differs(&obsHost[q], &last->observations[q])))
            continue;
        if (!weighted) return;
        changed.push_back(uint32_t(i));
    }
    if (changed.empty() || double(changed.size()) > kMaxChangedFraction * double(report.constraintPixels)) return;

    // The unknowns the changed pixels see (their rows' entries) ...
    const Support changedList(changed);
    GpuVector marks(elements, "stroke-unknowns");
    W->markThroughRows(false, changedList, marks);
    const std::vector<float> unknownMarks = marks.download();
    std::vector<uint32_t> moving;
    std::vector<float> movableHost(elements * 4, 0.0f);
    for (size_t e = 0; e < elements; ++e) {
        if (unknownMarks[4 * e] <= 0 || hullHost[4 * e] <= 0) continue;
        moving.push_back(uint32_t(e));
        std::fill_n(movableHost.begin() + std::ptrdiff_t(4 * e), 3, 1.0f);
    }
    if (moving.empty()) return;  // the stroke sees no unknown: nothing it asks can change
    // ... and the pixels that see those (their columns' entries).
    const Support movingList(moving);
    GpuVector pixelMarks(W->pixelCount(), "stroke-pixels");
    W->markThroughRows(true, movingList, pixelMarks);
    const std::vector<float> seen = pixelMarks.download();
    std::vector<uint32_t> pixels;
    for (size_t i = 0; i < W->pixelCount(); ++i)
        if (seen[4 * i] > 0 && anyPositive(&sqrtWHost[4 * i])) pixels.push_back(uint32_t(i));

    // The residuals over everything, then over the restricted supports: the moving unknowns' 6-
    // neighbours too, whose Laplacian rows read them. What is left out is a constant.
    auto measure = [&](std::vector<Vec3d>& perView, Vec3d& regularizers) {
        computeResiduals();
        perView.clear();
        for (size_t v = 0; v < views.size(); ++v) perView.push_back(ops.dot(rImg, rImg, W->viewRange(v)));
        regularizers = Vec3d(0.0);
        if (rLap.size() > 0) regularizers += ops.dot(rLap, rLap);
        if (rId.size() > 0) regularizers += ops.dot(rId, rId);
    };
    const double constantBefore = constant.x + constant.y + constant.z;
    std::vector<Vec3d> wholeViews, localViews;
    Vec3d wholeRegularizers, localRegularizers;
    measure(wholeViews, wholeRegularizers);
    const size_t pixelCount = pixels.size();
    useSupports(std::make_shared<const Support>(std::move(pixels)),
                std::make_shared<const Support>(withNeighbours(moving, hullHost, udims, cells)));
    movable.upload(movableHost);
    measure(localViews, localRegularizers);
    viewUntouched.assign(views.size(), Vec3d(0.0));
    for (size_t v = 0; v < views.size(); ++v) {
        for (int c = 0; c < 3; ++c) viewUntouched[v][c] = std::max(0.0, wholeViews[v][c] - localViews[v][c]);
        constant += viewUntouched[v];
    }
    for (int c = 0; c < 3; ++c) constant[c] += std::max(0.0, wholeRegularizers[c] - localRegularizers[c]);
    untouchedObjective = constant.x + constant.y + constant.z - constantBefore;

    report.local = {true, changed.size(), moving.size(), pixelCount};
    spdlog::info("solve: re-solve after a stroke: {} changed pixels see {} of {} hull unknowns, seen by {} of {} constrained pixels",
                 changed.size(), moving.size(), report.hullCount, pixelCount, report.constraintPixels);
}

void Solver::State::rememberSolve(const Volume& result, double solveMs) {
    if (!cache || lastKey.empty()) return;
    auto last = std::make_shared<LastSolve>();
    last->observations = std::move(obsHost);  // the solve is over: nothing reads them again
    last->weights = std::move(rawWeightHost);
    last->resultHash = unknownsHash(result, opt.unknown);
    cache->putLastSolve(lastKey, std::move(last), solveMs);  // what a re-solve of a stroke saves, at most
}

}  // namespace volstyle::core

// A solve's renders and rows, from the cache or made and kept there (solve_prefetch.h).
#include "core/solve/solve_prefetch.h"

#include <algorithm>
#include <functional>

#include "core/base/stopwatch.h"
#include "core/render/gpu_volume.h"
#include "core/solve/gpu_vector.h"
#include "core/solve/projector.h"

namespace volstyle::core {
namespace {

/// What renderBounds reads of a view (its target is not needed).
SolveView bare(const SolveView& v) { return {v.name, v.camera, Image(), std::nullopt, v.background}; }

/// A view's renders in `cache`: under the solve's own key (`own`), else under the exact volume's
/// (`exact`: made ahead of a solve); null where neither holds them.
struct FoundRenders {
    std::shared_ptr<const ViewRenders> renders;
    std::string own, exact;
    bool underOwnKey = false;
};
FoundRenders findViewRenders(SolveCache& cache, const VolumeKey& key, const Lighting& lighting, const SolveView& view,
                             const SolveOptions& options) {
    const Lighting seen = view.lightingFor(lighting);
    FoundRenders f{nullptr, rendersKey(key, seen, options, view.camera, options.analyzeReach),
                   exactRendersKey(key, seen, options, view.camera, options.analyzeReach)};
    f.renders = cache.findRenders(f.own);
    f.underOwnKey = f.renders != nullptr;
    if (!f.renders) f.renders = cache.findRenders(f.exact);
    return f;
}

/// Each view's rows of W for every pixel, for `options`' unknowns, kept in `cache` under the key a
/// solve whose every pixel has weight looks up (Solver::State::rowsMadeAhead finds them for any
/// other weights). A dense volume's only: a sparse one's unknowns are the bricks its solve picks.
int writeRowsAhead(GpuDevice& device, const std::function<GpuVolume&()>& gpu, const Volume& volume, const VolumeKey& key, const Lighting& lighting,
                   const std::vector<SolveView>& views, const SolveOptions& options, SolveCache& cache, const WorkBudget& budget) {
    // Only where the host reads the rows (a CPU rasterizer): a solve cuts them to its weighted
    // pixels there; a GPU writes a view's rows in milliseconds anyway.
    if (volume.isSparse() || options.rowCacheBytes == 0 || !solverKernelsOnHost(device)) return 0;
    const Int3 udims = options.resolution.value_or(volume.dims());
    const int channels = weightChannels(volume, lighting, options.unknown);
    int written = 0;
    for (const SolveView& v : views) {
        const size_t pixels = size_t(v.camera.width) * v.camera.height;
        const std::string k = rowsKey(key, lighting, options, udims, v.camera, channels, std::vector<uint8_t>(pixels, 1));
        if (cache.findRows(k)) continue;
        // Rows are the cache's largest entries: past half of it, work ahead would only push out
        // what solves left (renders, other sessions' rows) for rows it may push out itself.
        if (cache.bytes() > cache.budget() / 2) break;
        Projector W(device, gpu(), lighting, options.unknown, options.basis, udims, options.stepVoxels, options.exactTraversal);
        W.setMergeViews(false);
        W.setBudget(&budget);
        W.addView(v.camera);
        GpuVector every(pixels, "rows-ahead-mask");  // the solve's masked program, every pixel weighted
        every.upload(std::vector<float>(4 * pixels, 1.0f));
        W.cacheRows(options.rowCacheBytes, channels, &every);
        if (auto rows = W.rowsOf(0)) {
            cache.putRows(k, rows, rows->buildMs);
            ++written;
        }
    }
    return written;
}

}  // namespace

std::vector<std::shared_ptr<const ViewRenders>> cachedRenderBounds(GpuDevice& device, const Volume& volume, const VolumeKey& volumeKey,
                                                                   const Lighting& lighting, const std::vector<SolveView>& views,
                                                                   const SolveOptions& options, SolveCache* cache, const WorkBudget& budget) {
    std::vector<std::shared_ptr<const ViewRenders>> renders(views.size());
    std::vector<std::string> keys(views.size());
    for (size_t v = 0; v < views.size() && cache; ++v) {
        FoundRenders f = findViewRenders(*cache, volumeKey, lighting, views[v], options);
        keys[v] = std::move(f.own);
        renders[v] = std::move(f.renders);
        // Rendered ahead of the solve (the server's prefetch) of exactly this volume: kept under
        // this solve's key too, which the next solve (the unknowns changed) looks up.
        if (renders[v] && !f.underOwnKey) cache->putRenders(keys[v], renders[v], renders[v]->renderMs);
    }
    if (std::all_of(renders.begin(), renders.end(), [](const auto& r) { return r != nullptr; })) return renders;
    // A GpuVolume of their own: rendering through the solver's made the rows that follow 1.3 s
    // slower at 128³ (bench/solver_race (b); measured, cause not found), and this costs ~50 ms.
    GpuVolume own(volume);
    for (size_t v = 0; v < views.size(); ++v) {
        if (renders[v]) continue;
        renders[v] = renderBounds(device, own, lighting, {bare(views[v])}, options, options.analyzeReach, budget).front();
        if (cache) cache->putRenders(keys[v], renders[v], renders[v]->renderMs);
    }
    return renders;
}

PrefetchReport prefetchSolve(GpuDevice& device, const Volume& volume, const Lighting& lighting, const std::vector<SolveView>& views,
                             const SolveOptions& options, SolveCache& cache, const WorkBudget& budget, GpuVolume* given,
                             const VolumeKey* givenKey) {
    PrefetchReport report;
    // A sparse volume's solve grows an apron of bricks first, so its keys are not the uploaded
    // volume's; a light solve's set-up is its light volumes.
    if (options.lights.solve || views.empty() || volume.isSparse()) return report;
    const auto t0 = Clock::now();
    // Made under the exact volume's key, which serves a solve of any unknowns (the artist may pick
    // others than last time); found under the solve's own key too (the last solve left them).
    const VolumeKey key = givenKey ? *givenKey : volumeKeyOf(volume, options.unknown);
    std::vector<std::pair<std::string, SolveView>> todo;
    for (const SolveView& v : views)
        if (FoundRenders f = findViewRenders(cache, key, lighting, v, options); !f.renders) todo.emplace_back(std::move(f.exact), bare(v));
    report.viewsFound = int(views.size() - todo.size());
    std::unique_ptr<GpuVolume> own;  // uploaded once something is to be made; its light-depth volumes serve the rows too
    auto gpu = [&]() -> GpuVolume& {
        if (given) return *given;
        if (!own) own = std::make_unique<GpuVolume>(volume);
        return *own;
    };
    for (const auto& [k, v] : todo) {
        auto r = renderBounds(device, gpu(), lighting, {v}, options, options.analyzeReach, budget).front();
        cache.putRenders(k, r, r->renderMs);  // kept at once: an interrupted prefetch keeps what it finished
        ++report.viewsRendered;
    }
    report.rowsWritten = writeRowsAhead(device, gpu, volume, key, lighting, views, options, cache, budget);
    report.ms = msSince(t0);
    return report;
}

}  // namespace volstyle::core

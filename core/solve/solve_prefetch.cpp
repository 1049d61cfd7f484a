// A solve's renders, from the cache or made and kept there (solve_prefetch.h).
#include "core/solve/solve_prefetch.h"

#include "core/base/stopwatch.h"
#include "core/render/gpu_volume.h"

namespace volstyle::core {
namespace {

/// What renderBounds reads of a view (its target is not needed).
SolveView bare(const SolveView& v) { return {v.name, v.camera, Image(), std::nullopt, v.background}; }

}  // namespace

std::vector<std::shared_ptr<const ViewRenders>> cachedRenderBounds(GpuDevice& device, const Volume& volume, const VolumeKey& volumeKey,
                                                                   const Lighting& lighting, const std::vector<SolveView>& views,
                                                                   const SolveOptions& options, SolveCache* cache, const WorkBudget& budget,
                                                                   int* made) {
    std::vector<std::shared_ptr<const ViewRenders>> renders(views.size());
    std::vector<std::string> keys(views.size());
    bool missing = false;
    for (size_t v = 0; v < views.size() && cache; ++v) {
        const Lighting seen = views[v].lightingFor(lighting);
        keys[v] = rendersKey(volumeKey, seen, options, views[v].camera, options.analyzeReach);
        renders[v] = cache->findRenders(keys[v]);
        if (renders[v]) continue;
        // Rendered ahead of the solve (the server's prefetch) of exactly this volume: kept under
        // this solve's key too, which the next solve (the unknowns changed) looks up.
        renders[v] = cache->findRenders(exactRendersKey(volumeKey, seen, options, views[v].camera, options.analyzeReach));
        if (renders[v]) cache->putRenders(keys[v], renders[v], renders[v]->renderMs);
    }
    for (const auto& r : renders) missing |= !r;
    if (!missing) return renders;
    // A GpuVolume of their own: rendering through the solver's made the rows that follow 1.3 s
    // slower at 128³ (bench/solver_race (b); measured, cause not found), and this costs ~50 ms.
    GpuVolume own(volume);
    for (size_t v = 0; v < views.size(); ++v) {
        if (renders[v]) continue;
        renders[v] = renderBounds(device, own, lighting, {bare(views[v])}, options, options.analyzeReach, budget).front();
        if (cache) cache->putRenders(keys[v], renders[v], renders[v]->renderMs);  // kept at once: an interrupted prefetch keeps it
        if (made) ++*made;
    }
    return renders;
}

PrefetchReport prefetchSolve(GpuDevice& device, const Volume& volume, const Lighting& lighting, const std::vector<SolveView>& views,
                             const SolveOptions& options, SolveCache& cache, const WorkBudget& budget) {
    PrefetchReport report;
    if (options.lights.solve || views.empty()) return report;
    const auto t0 = Clock::now();
    // Made under the exact volume's key, which serves a solve of any unknowns (the artist may pick
    // others than last time); found under the solve's own key too (the last solve left them).
    const VolumeKey key = volumeKeyOf(volume, options.unknown);
    std::vector<std::pair<std::string, SolveView>> todo;
    for (const SolveView& v : views) {
        const Lighting seen = v.lightingFor(lighting);
        std::string exact = exactRendersKey(key, seen, options, v.camera, options.analyzeReach);
        if (!cache.findRenders(rendersKey(key, seen, options, v.camera, options.analyzeReach)) && !cache.findRenders(exact))
            todo.emplace_back(std::move(exact), bare(v));
    }
    report.viewsFound = int(views.size() - todo.size());
    if (todo.empty()) return report;
    GpuVolume own(volume);
    for (const auto& [k, v] : todo) {
        auto r = renderBounds(device, own, lighting, {v}, options, options.analyzeReach, budget).front();
        cache.putRenders(k, r, r->renderMs);  // kept at once: an interrupted prefetch keeps what it finished
        ++report.viewsRendered;
    }
    report.ms = msSince(t0);
    return report;
}

}  // namespace volstyle::core

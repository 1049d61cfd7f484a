// The solver's operator from rows (issue #12, #40): each view's rows of W taken from the solve
// cache or written (Projector::cacheRows), merged over the views, kept in the cache for the next
// solve at what they cost to write, and the vector work restricted to what the rows touch.
#include <algorithm>

#include "core/solve/host_columns.h"
#include "core/solve/solve_cache.h"
#include "core/solve/solver_state.h"

namespace volstyle::core {

void Solver::State::cacheOperator() {
    if (opt.rowCacheBytes == 0) return;
    const int channels = weightChannels(volume, lighting, opt.unknown);
    std::vector<std::string> keys(views.size());
    std::vector<std::vector<uint8_t>> masks(views.size());
    if (cache && volumeKey.grid.empty()) volumeKey = volumeKeyOf(volume, opt.unknown);  // buildObservations made it
    for (size_t v = 0; v < views.size() && cache; ++v) {
        masks[v] = weightedPixels(sqrtWHost, W->viewRange(v).first, W->viewRange(v).count);
        keys[v] = rowsKey(volumeKey, lighting, opt, udims, views[v].camera, channels, masks[v]);
    }
    // All views' rows as one (Projector::mergeRows, where the projector merges), kept under the
    // key of the rows it was made of and looked up first: found, it stands for every view's rows
    // (each view a range of it).
    std::string mergedKey = "merged";
    for (const auto& k : keys) mergedKey += "|" + k;
    auto merged = cache && views.size() > 1 && W->mergesViews() ? cache->findRows(mergedKey) : nullptr;
    const bool mergedFound = merged != nullptr;
    if (merged) W->adoptMergedRows(std::move(merged));
    std::vector<bool> adopted(views.size(), false), aheadAsTheyAre(views.size(), false);
    size_t adoptedEntries = 0;
    for (size_t v = 0; v < views.size() && cache && !W->merged(); ++v) {
        auto rows = cache->findRows(keys[v]);
        bool asTheyAre = false;
        if (!rows) rows = rowsMadeAhead(v, channels, masks[v], keys[v], asTheyAre);
        if (!rows) continue;
        adoptedEntries += rows->entries;
        adopted[v] = true;
        aheadAsTheyAre[v] = asTheyAre;
        W->adoptRows(v, std::move(rows));
    }
    // Each view's own rows stay beside the merged ones (a stroke's re-solve then rebuilds one
    // view's) while both fit in half the cache; past that, the merged rows alone.
    W->keepViewRowsWithin(cache ? cache->budget() / 2 : 0);
    // Rows only for the pixels that count (a weight > 0): the others' rows would be multiplied by 0.
    W->cacheRows(opt.rowCacheBytes, channels, &sqrtW);
    // What a miss would cost again: this solve's time writing rows (all of it for the merged
    // ones; a view built here, its share by entries of the views built here; a view taken from the
    // cache keeps the cost it was made at).
    const ProjectorStats& w = W->stats();
    const size_t builtEntries = w.cachedEntries > adoptedEntries ? w.cachedEntries - adoptedEntries : 0;
    for (size_t v = 0; v < views.size() && cache; ++v)
        if (auto rows = W->rowsOf(v); rows && !aheadAsTheyAre[v])  // (those are kept under the key work ahead wrote them under)
            cache->putRows(keys[v], rows, adopted[v] ? 0.0 : w.cacheMs * double(rows->entries) / double(std::max<size_t>(builtEntries, 1)));
    if (cache && W->merged()) cache->putRows(mergedKey, W->mergedRows(), w.cacheMs);
    report.rowCacheMs = w.cacheMs, report.rowCacheBytes = w.cacheBytes, report.cachedViews = w.cachedViews;
    const size_t taken = mergedFound ? views.size() : size_t(std::count(adopted.begin(), adopted.end(), true));
    report.writtenViews = w.cachedViews > taken ? w.cachedViews - taken : 0;
    if (!W->allCached()) return;
    // Every view gathers from its rows, which touch only constrained pixels and (for Wᵀ) the hull:
    // the vector work runs over those alone (hull voxels outside keep their start values, and
    // no operation reads a pixel without weight).
    std::vector<uint32_t> pixels, voxels;
    const std::vector<float>& w2 = sqrtWHost;
    for (size_t i = 0; i < W->pixelCount(); ++i)
        if (w2[4 * i] > 0 || w2[4 * i + 1] > 0 || w2[4 * i + 2] > 0) pixels.push_back(uint32_t(i));
    for (size_t e = 0; e < elements; ++e)
        if (hullHost[4 * e] > 0) voxels.push_back(uint32_t(e));
    useSupports(std::make_shared<const Support>(std::move(pixels)), std::make_shared<const Support>(std::move(voxels)));
}

std::shared_ptr<const SparseRows> Solver::State::rowsMadeAhead(size_t v, int channels, const std::vector<uint8_t>& mask,
                                                               const std::string& key, bool& asTheyAre) {
    // Work ahead (solve_prefetch.h) writes each view's rows for every pixel before the paint says
    // which have weight; where the host can read them, this view's are those rows' of its
    // weighted pixels (the same entries a masked fill writes).
    if (std::all_of(mask.begin(), mask.end(), [](uint8_t m) { return m != 0; })) return nullptr;  // that key missed already
    auto all = cache->findRows(rowsKey(volumeKey, lighting, opt, udims, views[v].camera, channels, std::vector<uint8_t>(mask.size(), 1)));
    if (!all || !all->hostMapped) return nullptr;
    auto rows = restrictRowsOnHost(all, mask);
    // Kept under this view's key only when cut down (a copy): the same rows twice would count
    // their bytes twice, and finding them again costs a look at their row starts.
    asTheyAre = rows == all;
    if (!asTheyAre) cache->putRows(key, rows, rows->buildMs);
    return rows;
}

void Solver::State::useSupports(std::shared_ptr<const Support> pixels, std::shared_ptr<const Support> voxels) {
    for (GpuVector* v : {&obs, &sqrtW, &rImg, &qImg, &tmpImg, &dImg, &rPrev}) v->setSupport(pixels);
    for (GpuVector* v : {&a, &aPrev, &s, &p, &hull, &rLap, &qLap, &dLap, &tmpU, &rId, &precond, &z, &movable})
        if (v->size() > 0) v->setSupport(voxels);  // (a regularizer's vectors exist only while it is on)
    W->setSupports(std::move(pixels), std::move(voxels));
}

}  // namespace volstyle::core

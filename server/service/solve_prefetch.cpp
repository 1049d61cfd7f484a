// Work ahead (issue #40): while the artist paints, the GL thread renders what the session's next
// solve needs first — each view's bound renders (core/solve/solve_prefetch.h), most of a first
// solve's set-up — so the solve finds them in the solve cache. It runs only while the GL thread
// has nothing else to do, and yields between chunks of a render to any request that arrives.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "core/solve/solve_cache.h"
#include "core/solve/solve_prefetch.h"
#include "server/service/service_context.h"

namespace volstyle::server {
namespace {

/// Cells a chunk of work ahead marches before it looks whether a request waits: ~0.1–0.2 s of
/// a lit 128³ render on llvmpipe (a whole 480² view is one chunk of ~2.5 s otherwise).
constexpr long long kPrefetchChunk = 1 << 14;

/// What a solve of `s` would render first: the session, its volume version and what it shows,
/// the solve's march and each view's camera and plate. Equal signatures: nothing new to prepare.
std::string signatureOf(const Session& s, const core::SolveOptions& o) {
    std::string sig = fmt::format("{}:{}:{}:{}:{}:{}", s.id, s.volume.version, s.shownRevision, o.stepVoxels, o.exactTraversal,
                                  o.analyzeReach);
    for (const SessionView& v : s.views.list)
        if (!v.frame) sig += "|" + v.id + ":" + core::cameraKey(v.camera) + fmt::format(":{}", static_cast<const void*>(v.background.get()));
    return sig;
}

}  // namespace

core::SolveCache* ServiceContext::solveCacheOnGl() {
    if (!solveCache && limits.solveCacheBytes > 0) solveCache = std::make_unique<core::SolveCache>(limits.solveCacheBytes);
    return solveCache.get();
}

void ServiceContext::prefetchSolve(const Session& s) {
    if (!limits.prefetchSolves || limits.solveCacheBytes == 0 || s.views.list.empty()) return;
    gl->whenIdle("prefetch:" + s.id, [this, id = s.id](core::GpuDevice& device, const std::atomic<bool>& yield) {
        return runPrefetch(id, device, yield);
    });
}

bool ServiceContext::runPrefetch(const std::string& sessionId, core::GpuDevice& device, const std::atomic<bool>& yield) {
    const std::shared_ptr<Session> s = sessions.find(sessionId);
    if (!s) {
        prefetched.erase(sessionId);
        return true;
    }
    core::Volume volume;
    core::Lighting lighting;
    std::vector<core::SolveView> views;
    core::SolveOptions options;
    std::string signature;
    {
        std::lock_guard lock(s->mutex);
        if (s->removed) return true;
        options = s->lastSolveOptions.value_or(core::SolveOptions{});
        signature = signatureOf(*s, options);
        if (prefetched[sessionId] == signature) return true;
        volume = s->volume.current;
        lighting = s->light.lighting;
        for (const SessionView& v : s->views.list)
            if (!v.frame) views.push_back({v.id, v.camera, core::Image(), std::nullopt, v.background});
    }
    core::SolveCache* cache = solveCacheOnGl();
    if (!cache || views.empty()) return true;
    try {
        const core::PrefetchReport r = core::prefetchSolve(device, volume, lighting, views, options, *cache,
                                                           WorkBudget(0, &yield).withChunksOf(kPrefetchChunk));
        prefetchedViews += uint64_t(r.viewsRendered);
        if (r.viewsRendered > 0)
            spdlog::info("session {}: rendered {} view(s) ahead of its next solve in {:.0f} ms ({} already kept)", sessionId,
                         r.viewsRendered, r.ms, r.viewsFound);
    } catch (const Cancelled&) {
        return false;  // a request came: the views done so far stay in the cache
    }
    prefetched[sessionId] = signature;
    return true;
}

}  // namespace volstyle::server

// Work ahead (issue #40): while the artist paints, the GL thread makes what the session's next
// solve needs first — each view's bound renders and rows of W (core/solve/solve_prefetch.h), most
// of a first solve's set-up — so the solve finds them in the solve cache. It runs only while the GL thread
// has nothing else to do, and yields between chunks of a render to any request that arrives.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "core/solve/solve_cache.h"
#include "core/solve/solve_prefetch.h"
#include "server/service/service_context.h"

namespace volstyle::server {
namespace {

/// How much finer than a bounded request's work ahead's chunks are (chunked_dispatch.h: 2^18
/// invocations of a march): 2^12 pixels, ~50 ms of a lit 128³ render on llvmpipe (a whole 480²
/// view is one chunk of ~2.5 s otherwise), what a request that arrives mid-chunk waits at most.
constexpr long long kPrefetchChunkDivisor = 64;

/// What a solve of `s` would make first depends on: its volume version and what it shows, the
/// solve's settings and each view's camera and plate. Equal signatures: nothing new to prepare.
std::string signatureOf(const Session& s, const core::SolveOptions& o) {
    std::string sig = fmt::format("{}:{}:{}:{}:{}:{}:{}:{}", s.volume.version, s.shownRevision, int(o.unknown), int(o.basis), o.stepVoxels,
                                  o.exactTraversal, o.analyzeReach, o.rowCacheBytes);
    if (o.resolution) sig += fmt::format(":{}x{}x{}", o.resolution->x, o.resolution->y, o.resolution->z);
    for (const SessionView& v : s.views.list)
        if (!v.frame) sig += "|" + v.id + ":" + core::cameraKey(v.camera) + fmt::format(":{}", static_cast<const void*>(v.background.get()));
    return sig;
}

/// What work ahead prepares a session's first solve for: the page's defaults (emission and
/// albedo). The renders serve any unknowns; the rows only these.
core::SolveOptions guessBeforeASolve() {
    core::SolveOptions o;
    o.unknown = core::Unknown::EmissionAlbedo;
    return o;
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
    if (!s || workAheadStopped) {
        prefetched.erase(sessionId);
        return true;
    }
    core::Volume volume;  // a copy for this try only: a view interrupted by requests may be tried many times
    core::Lighting lighting;
    std::vector<core::SolveView> views;
    core::SolveOptions options;
    std::string signature;
    std::shared_ptr<core::GpuVolume> gpu;  // the session's GPU copy: the light-depth volumes its renders made serve here too
    {
        std::lock_guard lock(s->mutex);
        if (s->removed) return true;
        options = s->lastSolveOptions.value_or(guessBeforeASolve());
        signature = signatureOf(*s, options);
        for (const SessionView& v : s->views.list)
            if (!v.frame) views.push_back({v.id, v.camera, core::Image(), std::nullopt, v.background});
        if (prefetched[sessionId].done == signature || views.empty()) return true;
        gpu = sessionGpu(*s);
        volume = s->volume.current;
        lighting = s->light.lighting;
    }
    core::SolveCache* cache = solveCacheOnGl();
    if (!cache) return true;
    PrefetchState& state = prefetched[sessionId];  // GL thread only
    if (state.pending != signature) state = {state.done, signature, core::volumeKeyOf(volume, options.unknown)};
    try {
        const core::PrefetchReport r = core::prefetchSolve(device, volume, lighting, views, options, *cache,
                                                           WorkBudget(0, &yield).withFinerChunks(kPrefetchChunkDivisor), gpu.get(), &state.key);
        prefetchedViews += uint64_t(r.viewsRendered);
        prefetchedRows += uint64_t(r.rowsWritten);
        if (r.viewsRendered + r.rowsWritten > 0)
            spdlog::info("session {}: ahead of its next solve, rendered {} view(s) ({} already kept) and wrote the rows of {}, in {:.0f} ms",
                         sessionId, r.viewsRendered, r.viewsFound, r.rowsWritten, r.ms);
    } catch (const Cancelled&) {
        return false;  // a request came: what is finished stays in the cache, the key for the next try
    }
    state = {signature, "", {}};
    return true;
}

}  // namespace volstyle::server

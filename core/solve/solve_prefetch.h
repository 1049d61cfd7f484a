#pragma once
/// \file solve_prefetch.h
/// A solve's renders made ahead of it (issue #40: what a person waits for on a first solve is
/// mostly its set-up, and most of that is each view's bound renders, reach.h). Those depend on
/// the cameras, the volume, the lighting and the settings, never on the paint: the server makes
/// them while the artist paints (server/service/solve_prefetch_service.cpp), and the solve finds
/// them in its SolveCache under the keys it would have made them under. GL thread only.

#include <memory>
#include <vector>

#include "core/base/work_budget.h"
#include "core/gpu/gpu_device.h"
#include "core/solve/reach.h"
#include "core/solve/solve_cache.h"

namespace volstyle::core {

/// Each view's bound renders (renderBounds), from `cache` where it holds them; made (and kept
/// there, each as soon as it is done) otherwise. `cache` may be null. `volumeKey`:
/// volumeKeyOf(volume, options.unknown), needed only with a cache. Throws as `budget` says between
/// chunks; the views finished by then stay in the cache. `made`: how many were rendered here.
std::vector<std::shared_ptr<const ViewRenders>> cachedRenderBounds(GpuDevice& device, const Volume& volume, const VolumeKey& volumeKey,
                                                                   const Lighting& lighting, const std::vector<SolveView>& views,
                                                                   const SolveOptions& options, SolveCache* cache,
                                                                   const WorkBudget& budget = WorkBudget(), int* made = nullptr);

/// What prefetchSolve() did.
struct PrefetchReport {
    int viewsRendered = 0;  ///< made now
    int viewsFound = 0;     ///< in the cache already
    double ms = 0;
};

/// Makes what a solve of `views` (targets not needed) under `options` would render first, into
/// `cache`. Nothing for a light solve (its set-up is the light volumes). Throws as `budget` says.
PrefetchReport prefetchSolve(GpuDevice& device, const Volume& volume, const Lighting& lighting, const std::vector<SolveView>& views,
                             const SolveOptions& options, SolveCache& cache, const WorkBudget& budget = WorkBudget());

}  // namespace volstyle::core

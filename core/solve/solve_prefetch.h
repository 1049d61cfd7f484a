#pragma once
/// \file solve_prefetch.h
/// A solve's set-up made ahead of it (issue #40: what a person waits for on a first solve is
/// mostly its set-up: each view's bound renders, reach.h, and its rows of W). Those depend on the
/// cameras, the volume, the lighting and the settings, hardly on the paint: the server makes them
/// while the artist paints (server/service/solve_prefetch.cpp), and the solve finds them in its
/// SolveCache. The renders serve a solve of any unknowns; the rows, written for every pixel on a
/// CPU rasterizer, serve the unknowns they were written for and any pixels' weights (the solver
/// cuts them down with restrictRowsOnHost). Dense volumes only. GL thread only.

#include <memory>
#include <vector>

#include "core/base/work_budget.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/solve/reach.h"
#include "core/solve/solve_cache.h"

namespace volstyle::core {

/// Each view's bound renders (renderBounds), from `cache` where it holds them; made (and kept
/// there, each as soon as it is done) otherwise. `cache` may be null. `volumeKey`:
/// volumeKeyOf(volume, options.unknown), needed only with a cache. Throws as `budget` says between
/// chunks; the views finished by then stay in the cache.
std::vector<std::shared_ptr<const ViewRenders>> cachedRenderBounds(GpuDevice& device, const Volume& volume, const VolumeKey& volumeKey,
                                                                   const Lighting& lighting, const std::vector<SolveView>& views,
                                                                   const SolveOptions& options, SolveCache* cache,
                                                                   const WorkBudget& budget = WorkBudget());

/// What prefetchSolve() did.
struct PrefetchReport {
    int viewsRendered = 0;  ///< made now
    int viewsFound = 0;     ///< in the cache already
    int rowsWritten = 0;    ///< views whose rows were written now
    double ms = 0;
};

/// Makes what a solve of `views` (targets not needed) under `options` would make first, into
/// `cache`: each view's renders, then (on a CPU rasterizer, options.rowCacheBytes > 0) its rows for
/// every pixel while the cache is under half full. Nothing for a light solve (its set-up is the
/// light volumes) or a sparse volume (its solve's keys follow the apron it grows). Throws as `budget` says
/// between chunks; what is finished stays in the cache. `gpu`: `volume` on the GPU already (the
/// server's copy of a session's, whose light-depth volumes its renders made); null: uploaded here.
/// `key`: volumeKeyOf(volume, options.unknown), if the caller keeps it (a prefetch that yields is
/// run again: hashing a 128³ volume's grids takes ~0.1 s); null: made here.
PrefetchReport prefetchSolve(GpuDevice& device, const Volume& volume, const Lighting& lighting, const std::vector<SolveView>& views,
                             const SolveOptions& options, SolveCache& cache, const WorkBudget& budget = WorkBudget(),
                             GpuVolume* gpu = nullptr, const VolumeKey* key = nullptr);

}  // namespace volstyle::core

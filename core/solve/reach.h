#pragma once
/// \file reach.h
/// How much of the paint the chosen unknowns can reach (issue #10). Bounds limit what a solve can
/// do: emission (≥ 0) only adds light, so a pixel can get no darker than the render without
/// emission; albedo (in [0, 1]) only moves a pixel between the renders with albedo 0 and 1;
/// both together reach anything above the render with neither; extinction keeps a pixel between
/// L_m and the background. The part of target − render outside those per-pixel intervals is
/// out of reach whatever the solve does: reported per view, with the unknowns that would reach
/// more of it. GL thread only.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/base/work_budget.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_options.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// Weighted RMS of the distance from `target` to the interval [lo, hi] (per pixel and channel),
/// as the solver measures residuals: per channel √(Σ w d² / Σ w), averaged over channels with
/// weight. `weights` per pixel (target alpha × weight image); `hi` may be +inf.
double unreachableRms(const Image& target, const std::vector<double>& weights, const Image& lo, const Image& hi);

/// One view rendered with the unknowns' terms at their bounds. The extinction fixed, a render is
/// linear in emission and albedo: beauty = emission + scattering + T·background, with the
/// scattering proportional to the albedo. So two renders give them all: the volume as it is (in
/// layers) and with albedo 1. The solver's observations take their fixed part from here too.
struct ViewRenders {
    Image now;         ///< the volume as it is
    Image noEmission;  ///< now − emission
    Image albedo0;     ///< now − scattering
    Image albedo1;     ///< albedo0 + the scattering with albedo 1 (only with `withAlbedoOne`)
    Image neither;     ///< T·background: no emission, albedo 0
    Image background;  ///< the background alone (no medium)
    double renderMs = 0;  ///< what the render took (what a miss in SolveCache costs again)
};

/// One render per view (with `withAlbedoOne`, the albedo-1 scattering from the same march), under
/// `options`' step and traversal, of the volume already on the GPU (the solver's own upload).
/// Throws as `budget` says between chunks.
std::vector<std::shared_ptr<const ViewRenders>> renderBounds(GpuDevice& device, GpuVolume& volume, const Lighting& lighting,
                                      const std::vector<SolveView>& views, const SolveOptions& options, bool withAlbedoOne,
                                      const WorkBudget& budget = WorkBudget());

/// Fills `report.reach` for solving `options.unknown` toward `views` from renderBounds() (with
/// albedo 1). Renders kept from an earlier solve (SolveCache) are exact for the chosen unknowns'
/// own bounds; the other candidates' bounds then hold the unknowns as that solve started.
void analyzeReach(const std::vector<std::shared_ptr<const ViewRenders>>& renders, const std::vector<SolveView>& views,
                  const SolveOptions& options, SolveReport& report);
/// The same, rendering first.
void analyzeReach(GpuDevice& device, const Volume& volume, const Lighting& lighting,
                  const std::vector<SolveView>& views, const SolveOptions& options, SolveReport& report);

}  // namespace volstyle::core

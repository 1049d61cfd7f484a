#pragma once
/// \file reach.h
/// How much of the paint the chosen unknowns can reach (issue #10). Bounds limit what a solve can
/// do: emission (≥ 0) only adds light, so a pixel can get no darker than the render without
/// emission; albedo (in [0, 1]) only moves a pixel between the renders with albedo 0 and 1;
/// both together reach anything above the render with neither; extinction keeps a pixel between
/// L_m and the background. The part of target − render outside those per-pixel intervals is
/// out of reach whatever the solve does: reported per view, with the unknowns that would reach
/// more of it. GL thread only.

#include <optional>
#include <string>
#include <vector>

#include "core/gpu/gpu_device.h"
#include "core/render/params.h"
#include "core/solve/solve_options.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// Weighted RMS of the distance from `target` to the interval [lo, hi] (per pixel and channel),
/// as the solver measures residuals: per channel √(Σ w d² / Σ w), averaged over channels with
/// weight. `weights` per pixel (target alpha × weight image); `hi` may be +inf.
double unreachableRms(const Image& target, const std::vector<double>& weights, const Image& lo, const Image& hi);

/// Fills `report.reach` for solving `options.unknown` of `volume` toward `views`: a few renders
/// per view (the volume without emission, with albedo 0 and 1).
void analyzeReach(GpuDevice& device, const Volume& volume, const Lighting& lighting,
                  const std::vector<SolveView>& views, const SolveOptions& options, SolveReport& report);

}  // namespace volstyle::core

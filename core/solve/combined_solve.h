#pragma once
/// \file combined_solve.h
/// "This look": the lighting and the volume together (SPEC §8, issue #13 item 3). Alternating
/// block descent between the two linear solvers: the environment lobes' radiances with the volume
/// fixed (LightSolver), then the volume's unknowns (emission, albedo or both) under that lighting
/// (Solver), for a number of rounds. Each block solve lowers the same objective — the targets'
/// weighted squared error, with each block's regularizers — so the rounds never raise it.
/// The joint alternative (one CGLS over [T | W]) is not built; docs/LIGHTING.md says why.
/// GL thread only.

#include <atomic>
#include <functional>
#include <vector>

#include "core/gpu/gpu_device.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_options.h"
#include "core/volume/volume.h"

namespace volstyle::core {

struct CombinedSolveResult {
    Volume volume;                 ///< the volume with its solved unknowns
    std::vector<Vec3d> radiance;   ///< the lobes' radiances
    int rounds = 0;
    /// Mean over views of the weighted RMS error: at the start, then after each block solve
    /// (lights, volume, lights, volume, …). The objective (data and regularizers) never rises;
    /// the data alone may give back a little where a regularizer shrinks the unknowns.
    std::vector<double> rmsHistory;
    double totalMs = 0;
};

struct CombinedProgress {
    int round = 0;
    const char* block = "";  ///< "lights" or the volume unknown's name
    SolveProgress inner;     ///< the block solve's own progress
};

/// Alternates `rounds` times (at least 1), lights first. `volumeOptions.unknown` is emission,
/// albedo or both (extinction is refused); its other fields serve both blocks (iterations per block
/// solve, tolerance, regularization, step, views). Throws InvalidArgument, Cancelled.
CombinedSolveResult solveLightsAndVolume(GpuDevice& device, const Volume& volume, const Lighting& lighting,
                                         const std::vector<SolveView>& views, const SolveOptions& volumeOptions, int rounds,
                                         const std::function<void(const CombinedProgress&)>& progress = {},
                                         const std::atomic<bool>* cancel = nullptr);

}  // namespace volstyle::core

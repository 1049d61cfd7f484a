#pragma once
/// \file render_settings.h
/// The ray marcher's quality and speed settings, and the march step's one range. GL-free.

#include <optional>

#include "core/scene/field_problem.h"

namespace volstyle::core {

/// The march step's range, in voxels, for every march (renders, solves, previews): the one
/// place it is stated (stepProblem; the schema's solve_options.step says the same, checked by
/// tests/unit/schema_limits_test.cpp). Finer than 0.05 multiplies a solve's rows past any use.
inline constexpr double kMinStepVoxels = 0.05, kMaxStepVoxels = 8;
/// The problem with a march step (field "step"), if any.
std::optional<FieldProblem> stepProblem(double stepVoxels);

struct RenderSettings {
    double stepVoxels = 0.5;        ///< march step, in voxels of the extinction grid
    bool skipEmptySpace = true;     ///< jump over occupancy bricks with zero extinction
    /// Early ray termination budget ε. A ray stops once its transmittance T is below ε and the
    /// most it could still gather, T·L_max (L_max bounds emission + in-scattering + background),
    /// is below ε of what it has gathered — or once T < 1e-3·ε. So the radiance lost is below ε
    /// relative (alpha below ε absolute). 0 marches every ray to its end.
    double terminationThreshold = 1e-5;
    bool hardwareFilter = false;    ///< sample with the texture unit (fast, 8-bit weights on GPUs)
    /// One segment per voxel cell crossed (Amanatides–Woo) instead of equal steps of stepVoxels.
    bool exactTraversal = false;
    /// Follow the volume's refractive_index grid (issue #16). Off, or with no grid or a constant
    /// one, rays are straight and the straight-ray kernels run unchanged.
    bool refraction = true;

    void validate() const;
};

}  // namespace volstyle::core

#pragma once
/// \file light_solver.h
/// Light reconstruction (SPEC §8; TVCG Sec. 4.4, 5.3): the environment lobes' radiances c ≥ 0
/// whose single scattering, added to what the rest of the scene gives (emission, the sun and
/// lights, the background), matches painted targets; the volume stays fixed. Each RGB channel is
///
///   minimise (1/Σw) Σ_k w_k (T c − (o − f))_k² + (λ_lap/|E|) Σ_{(i,j)∈E} (u_i − u_j)²
///            + (λ_0/N) ‖u‖² + (λ_1/N) ‖u − 1‖²,   u = c Ω̄/4π,
///   subject to c ≥ 0,
///
/// with T the lights projector (lights_project.comp), f the fixed part rendered once, E the
/// pairs of neighbouring lobes (each lobe's 6 nearest), Ω̄ the mean solid angle of a lobe (u_i is
/// about what lobe i adds to a pixel of a white opaque medium, so the weights mean what the volume
/// solver's do, whatever N) and λ_lap, λ_0, λ_1 the options' `laplacian`, `l2`, `toward_one`. Solved by the same bounded CGLS as the volume solver (solver.h): an
/// active set freezes lobes at 0 whose gradient points outward, a step is cut where a free lobe
/// reaches 0 and that channel restarts from the gradient, so the objective never rises. The N
/// unknowns live on the host; pixels on the GPU for T and Tᵀ, on the host in between (double).
/// GL thread only.

#include <atomic>
#include <functional>
#include <memory>
#include <vector>

#include "core/gpu/gpu_device.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_options.h"
#include "core/volume/volume.h"

namespace volstyle::core {

struct LightSolveResult {
    std::vector<Vec3d> radiance;  ///< per lobe, linear RGB (the lighting's environment.radiance)
    SolveReport report;
    double lightVolumeMs = 0;   ///< building the lobes' light volumes (0 when cached)
    size_t lightVolumeBytes = 0;
};

/// The lighting a lights solve starts from: `lighting` with its environment on `options.lobes`
/// lobes (0: its own count, 16 if it has none) over `options.domain` (unset: its own). The start
/// is its radiances when the basis is unchanged, else its map's projection, else black.
Lighting lightingForLightSolve(const Lighting& lighting, const SolveOptions::Lights& options);

class LightSolver {
public:
    /// `lighting.environment` names the basis (lobes, domain, light-volume resolution) and the
    /// start (its radiances, or its map's projection; none: 0). Uses `options`' iterations,
    /// tolerance, step, regularization (laplacian: between neighbouring lobes; l2), views and
    /// enforceBounds. Throws InvalidArgument for bad views, a view name with no target, no lobes.
    /// `cancel`, if given, is also checked while the light volumes and the fixed part are built
    /// (between lobes: N light-depth passes can take minutes), throwing Cancelled.
    LightSolver(GpuDevice& device, const Volume& volume, const Lighting& lighting, std::vector<SolveView> views,
                SolveOptions options, const std::atomic<bool>* cancel = nullptr);
    ~LightSolver();

    using ProgressCallback = std::function<void(const SolveProgress&)>;
    /// Runs to a stopping rule; `cancel` is checked between iterations (throws Cancelled).
    LightSolveResult run(const ProgressCallback& progress = {}, const std::atomic<bool>* cancel = nullptr);
    /// The current radiances (for previews; call from the progress callback).
    std::vector<Vec3d> currentRadiance() const;

    struct State;  ///< internal to light_solver.cpp (its bounded CGLS problem reads it)

private:
    std::unique_ptr<State> m_state;
};

}  // namespace volstyle::core

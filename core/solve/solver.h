#pragma once
/// \file solver.h
/// The painting solver (TVCG Sec. 4–5, SPEC §2): finds the emission, albedo, both, or the
/// extinction whose single-scattering renderings match painted targets in the weighted
/// least-squares sense, with regularizers and bounds.
///
/// Method: CGLS on the stacked system [√(w/Σw)·W; √(λ_lap/M)·L; √((λ0+λ1)/M)·I] a ≈
/// [√(w/Σw)·o; 0; √((λ0+λ1)/M)·t] (t = λ1/(λ0+λ1)), three channels in lockstep, with an active
/// set for the bounds: variables at a bound whose gradient points outward are frozen; a step is
/// cut where the first free variable meets its bound, and that channel restarts from the
/// gradient. Every step is along a descent direction with at most the exact line-search length,
/// so the objective never rises. All vectors live on the GPU; reductions are float64.
///
/// A Solver works on its own copy of the volume: a cancelled or failed solve changes nothing.
/// It holds the light-depth volumes it binds for its whole life, so other GPU work on the device
/// between iterations (renders of other sessions, previews) cannot disturb it. GL thread only.

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

class SolveCache;

/// Reference methods over a Solver's set-up (the same operators, observations, weights, hull and
/// bounds), for the benchmarks that race CGLS against them (bench/solver_race, issue #12). They
/// minimize the data term only: the regularization must be 0.
enum class BaselineMethod {
    /// Adam on the gradient −Aᵀr (β1 = 0.9, β2 = 0.999, ε = 1e-8), `rate` the step, clamped to
    /// the bounds after each step: what a differentiable-rendering solver does.
    Adam,
    /// SART (Andersen & Kak 1984): per view v, a += rate · V_v⁻¹ A_vᵀ M_v⁻¹ (b_v − A_v a) with M the
    /// rows' and V_v the view's columns' sums, clamped to the bounds; an iteration sweeps every
    /// view once, in an order that spreads consecutive views apart.
    Sart,
};

struct SolveResult {
    Volume volume;  ///< the input volume with the solved property replaced
    SolveReport report;
};

/// The inactive bricks a solve of `unknown` on sparse `volume` activates for its unknowns: the
/// hull's apron (a voxel around the medium) for emission and albedo, every brick next to an
/// active one for extinction. Empty for a dense volume. Callers that keep several volumes on one
/// layout (key frames) activate them up front, so the solve's result keeps their layout.
std::vector<Int3> sparseSolveApron(const Volume& volume, Unknown unknown);

class Solver {
public:
    /// Validates everything up front (throws InvalidArgument): options, views (a target per view,
    /// sizes matching the camera, no NaN/Inf), the unknown's requirements. With `cache`, each
    /// view's rows of W and bound renders come from an earlier solve where their keys match, and
    /// what this solve makes is left there for the next (solve_cache.h).
    Solver(GpuDevice& device, const Volume& volume, const Lighting& lighting, std::vector<SolveView> views,
           SolveOptions options, SolveCache* cache = nullptr);
    ~Solver();

    using ProgressCallback = std::function<void(const SolveProgress&)>;
    /// Runs to a stopping rule. `cancel` is checked between iterations (throws Cancelled).
    SolveResult run(const ProgressCallback& progress = {}, const std::atomic<bool>* cancel = nullptr);

    /// Runs `iterations` of a baseline method instead (call instead of run()); the report holds the
    /// objective CGLS minimizes after each. Throws InvalidArgument with regularization on.
    SolveResult runBaseline(BaselineMethod method, int iterations, double rate, const ProgressCallback& progress = {});

    /// The volume with the current iterate (for previews; call from the progress callback).
    Volume currentVolume();

private:
    struct State;
    std::unique_ptr<State> m_state;
};

}  // namespace volstyle::core

#pragma once
/// \file solve_options.h
/// What a solve is asked to do (SPEC §2), GL-free: protocol/ parses it from JSON, the CLI from
/// flags. `check()` lists every problem with the JSON field it belongs to.

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "core/base/name_table.h"
#include "core/image/image.h"
#include "core/math/vec.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_types.h"

namespace volstyle::core {

/// Regularizer weights (TVCG Sec. 5.2; "weak weights, i.e. 2^-9"), each averaged over the
/// unknown voxels so they do not depend on resolution.
struct Regularization {
    double laplacian = 0.002;  ///< ‖L a‖²: smoothness within the hull
    double l2 = 0;             ///< ‖a‖²: small values
    double towardOne = 0;      ///< ‖a − 1‖²: values near one
};

/// How the bounds are kept (the benchmark compares them; the default is the faster).
enum class BoundsMethod {
    Projected,   ///< try clamp(a + αp); keep it where it lowers the objective, else cut
    CutAtBound,  ///< always cut the step where the first free variable meets its bound
};

struct SolveOptions {
    Unknown unknown = Unknown::Emission;
    BasisType basis = BasisType::Trilinear;
    Regularization regularization;  ///< for every unknown, unless overridden below
    /// Per-unknown weights of a joint solve (TVCG Sec. 5.2: "we can specify which element to
    /// favor and, e.g., minimize emission"); absent: `regularization`.
    std::optional<Regularization> emissionRegularization, albedoRegularization;
    BoundsMethod boundsMethod = BoundsMethod::Projected;
    int maxIterations = 30;
    double tolerance = 1e-4;    ///< stop when an iteration lowers the objective by less than this, relatively
    /// Stop once two iterations in a row change no constrained pixel of any view by more than
    /// this (linear radiance; 0.5/255 is half an 8-bit step at white, about a third at mid-grey
    /// in sRGB): the error left no longer changes what a user sees. 0: off.
    double visibleChange = 0.5 / 255;
    double stepVoxels = 0.5;
    bool exactTraversal = false;  ///< "traversal": "march" (equal steps) or "exact" (voxel cells)
    bool useHull = true;        ///< "hull": "extinction" (true) or "none"
    std::optional<Int3> resolution;       ///< unknown grid; default: the extinction grid's
    std::optional<Vec3d> mediumRadiance;  ///< L_m, required for extinction solves (Sec. 4.2.4)
    std::vector<std::string> views;       ///< which views; empty: all with a target
    bool enforceBounds = true;  ///< albedo in [0,1], emission and extinction ≥ 0 (tests may lift it)
    bool precondition = true;   ///< CGLS with the column scaling D² = 1/(AᵀA1) (solver_setup.cpp)
    /// Coarse to fine: this many iterations on half the unknowns, pixels and samples per axis
    /// first, whose result is the fine solve's warm start (0: none; solver_setup.cpp).
    int coarseIterations = 0;
    /// GPU memory for the views' cached rows of W and their transpose (sparse_rows.h); views
    /// past it run matrix-free, and 0 runs every view matrix-free.
    size_t rowCacheBytes = size_t(1) << 30;
    /// Whether the views' cached rows are merged into one (Projector::setMergeViews); default: on
    /// a GPU, not on a CPU rasterizer (its host gathers view by view at the same cost).
    std::optional<bool> mergeViewRows;
    bool analyzeReach = true;   ///< report what the paint asks that the unknowns cannot give (reach.h)
    /// Re-solve after a stroke (solver_local.cpp): when the solve starts from the volume the last
    /// solve with the same settings left (SolveCache) and only some pixels' targets or weights
    /// changed, only the unknowns those pixels see move, and only the pixels that see them are
    /// recomputed. false: every solve moves every unknown.
    bool localResolve = true;
    /// A prior: weight · ‖a − p‖² (per hull unknown, scaled as `l2`), p three values (RGB) per
    /// element of the unknown grid, blocks in order. The key-frame solver (keyframe_solver.h)
    /// couples neighbouring frames through it. Needs the volume's own grid (no `resolution`),
    /// no coarse iterations; a solve with a prior never re-solves locally.
    struct Prior {
        std::shared_ptr<const std::vector<float>> values;
        double weight = 0;
    } prior;
    /// Light reconstruction (SPEC §8; "unknowns": ["lights"] alone or with emission/albedo): the
    /// environment lobes' radiances, alone (LightSolver) or in turn with `unknown`
    /// (solveLightsAndVolume, `lightRounds` rounds). `lobes` 0 keeps the lighting's own count
    /// (16 if it has none).
    struct Lights {
        bool solve = false;
        bool withVolume = false;
        int lobes = 0;
        std::optional<LobeDomain> domain;
        int rounds = 8;
        /// The lobes are the background too (Background::fromLobes): what the views show behind
        /// the volume is solved with the lighting. Also on when the lighting says so.
        bool background = false;
    } lights;

    std::vector<FieldProblem> check() const;
    void validate() const;  ///< throws InvalidArgument listing check()'s problems
    /// The weights for the emission or albedo block (extinction: `regularization`).
    const Regularization& regularizationFor(Unknown block) const;
};

/// One painted view: the camera, the target (linear RGB; alpha = weight) and optional weights.
struct SolveView {
    std::string name;
    Camera camera;
    Image target;
    std::optional<Image> weights;  ///< single-channel (R used), multiplies the target's alpha
    /// The view's background plate (SPEC §1; the camera's size): what lies behind the volume in
    /// this view, replacing the lighting's background colour or map. Null: the lighting's.
    std::shared_ptr<const Image> background = nullptr;
    /// Pixels of the target left out because the image under the paint was clipped there
    /// (core/image/clipped_pixels.h): the reach report says so instead of blaming the unknowns.
    size_t clippedPixels = 0;

    /// The lighting this view is rendered under: `lighting` with the view's plate, if any.
    Lighting lightingFor(const Lighting& lighting) const;
    /// Throws InvalidArgument naming the view: a bad camera, a target, weight or background
    /// image whose size differs from the camera's, non-finite or negative background values.
    void validate() const;
};

/// What a solve is doing (issue #37: a person sees the first second of a solve, not "queued").
enum class SolvePhase { PreparingViews, AnalysingReach, Iterating, Writing };
inline constexpr Named<SolvePhase> kSolvePhases[] = {
    {SolvePhase::PreparingViews, "preparing_views"},
    {SolvePhase::AnalysingReach, "analysing_reach"},
    {SolvePhase::Iterating, "iterating"},
    {SolvePhase::Writing, "writing"},
};
static_assert(coversInOrder(kSolvePhases), "a name for every phase");
constexpr const char* solvePhaseName(SolvePhase p) { return nameOf(kSolvePhases, p); }

/// Reported after every iteration, and when a phase begins (then iteration is the last one done).
struct SolveProgress {
    SolvePhase phase = SolvePhase::Iterating;
    int iteration = 0;
    double objective = 0;
    std::vector<double> rmsPerView;  ///< weighted RMS error of each view (mean over RGB)
    double elapsedMs = 0;
    double forwardMs = 0, adjointMs = 0, vectorMs = 0;  ///< this iteration's split
};

/// Why a solve stopped. The API reports the snake_case names of kStopReasons.
enum class StopReason {
    None,                ///< still running (never in a finished report)
    Converged,           ///< an iteration lowered the objective by less than the tolerance
    Stagnated,           ///< no decrease three iterations in a row
    Settled,             ///< two iterations in a row changed no pixel visibly (visibleChange)
    MaxIterations,       ///< max_iterations reached
    ZeroGradient,        ///< the gradient over the free variables vanished: a minimum
    NoConstraints,       ///< no pixel has a positive weight
    EmptyHull,           ///< no unknown can influence any pixel
    NumericalBreakdown,  ///< the objective became non-finite; the last finite iterate is kept
};
inline constexpr Named<StopReason> kStopReasons[] = {
    {StopReason::None, "none"},
    {StopReason::Converged, "converged"},
    {StopReason::Stagnated, "stagnated"},
    {StopReason::Settled, "settled"},
    {StopReason::MaxIterations, "max_iterations"},
    {StopReason::ZeroGradient, "zero_gradient"},
    {StopReason::NoConstraints, "no_constraints"},
    {StopReason::EmptyHull, "empty_hull"},
    {StopReason::NumericalBreakdown, "numerical_breakdown"},
};
static_assert(coversInOrder(kStopReasons), "a name for every reason");
constexpr const char* stopReasonName(StopReason r) { return nameOf(kStopReasons, r); }
std::ostream& operator<<(std::ostream& out, StopReason r);

/// What the paint asks that the unknowns cannot give (reach.h).
struct ReachReport {
    std::vector<double> unreachableRms;  ///< per view, with the chosen unknowns (same units as finalRms)
    /// Per view, for each unknown set that could be chosen instead (emission, albedo, both).
    std::vector<std::vector<std::pair<Unknown, double>>> alternatives;
    std::optional<Unknown> suggestion;  ///< unknowns that reach clearly more of the paint, if any
    std::string advice;                 ///< one sentence for people (empty: the paint is within reach)
    size_t clippedPixels = 0;           ///< target pixels left out as clipped, all views together
    double ms = 0;                      ///< the analysis' time (its renders)
};

struct SolveReport {
    int iterations = 0;
    StopReason stopReason = StopReason::None;
    double initialObjective = 0, finalObjective = 0;
    std::vector<double> initialRms, finalRms;
    std::vector<double> objectiveHistory;  ///< [0] before the first iteration
    size_t unknownCount = 0, hullCount = 0;
    size_t constraintPixels = 0;
    size_t ignoredPixels = 0;   ///< extinction: ratio not positive, or L_bg = L_m (weight 0)
    size_t clampedPixels = 0;   ///< extinction: ratio above 1, clamped to 1
    double totalMs = 0, forwardMs = 0, adjointMs = 0, vectorMs = 0;
    int coarseIterations = 0;  ///< the coarse start's iterations (SolveOptions::coarseIterations)
    double coarseMs = 0;       ///< its whole time, set-up included
    double rowCacheMs = 0;     ///< writing the views' cached rows of W (SolveOptions::rowCacheBytes)
    /// The set-up before the first iteration, phase by phase (name, ms) in the order they ran: what
    /// a person waits for before the solve moves (issue #40).
    std::vector<std::pair<std::string, double>> setupPhases;
    double setupMs() const {
        double ms = 0;
        for (const auto& [name, t] : setupPhases) ms += t;
        return ms;
    }
    size_t rowCacheBytes = 0;  ///< the GPU memory they take
    size_t cachedViews = 0;    ///< views whose W and Wᵀ gather from them (the rest: matrix-free)
    size_t writtenViews = 0;   ///< of those, the views whose rows this solve wrote (the others came from the SolveCache)
    /// A re-solve after a stroke (SolveOptions::localResolve): what changed and what moved.
    struct Local {
        bool active = false;       ///< this solve moved only the unknowns the changed pixels see
        size_t changedPixels = 0;  ///< pixels whose target or weight differ from the last solve's
        size_t unknowns = 0;       ///< hull unknowns they see (the only ones that move)
        size_t pixels = 0;         ///< constrained pixels that see those (the only ones recomputed)
    } local;
    ReachReport reach;
};

const char* unknownName(Unknown u);

/// A view's weighted RMS error (the mean over its constrained channels) from r2, its sum of the
/// squared residuals √(w/Σw)·(A a − o), with Σw over all views (`weightSum`) and over this one.
double viewRms(const Vec3d& r2, const Vec3d& weightSum, const Vec3d& viewWeightSum);

}  // namespace volstyle::core

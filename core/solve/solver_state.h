#pragma once
/// \file solver_state.h
/// The solver's working state (internal to core/solve): the problem set up once on the GPU
/// (solver_setup.cpp: observations, weights, hull, bounds, regularizers, warm start) and the
/// CGLS vectors the iterations update (solver.cpp).

#include <memory>
#include <vector>

#include "core/base/stopwatch.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/solve/bounded_cgls.h"
#include "core/solve/gpu_vector.h"
#include "core/solve/projector.h"
#include "core/solve/reach.h"
#include "core/solve/solve_cache.h"
#include "core/scene/solve_options.h"
#include "core/solve/solver.h"

namespace volstyle::core {

/// Regularizer rows of one block of unknowns (emission, albedo or extinction): √(λ_lap/M) L and
/// √((λ0+λ1)/M) (a − t) with t = λ1/(λ0+λ1), M the block's hull unknowns (SPEC §2).
struct BlockRegularizer {
    Range range;
    double cLap = 0, cId = 0, target = 0;
    /// With a prior (SolveOptions::prior): the target per unknown (4 per element of `range`:
    /// (λ1·1 + λp·p)/λ), else empty and `target` holds for every unknown.
    std::vector<float> targets;
};

/// The volume solve as bounded CGLS sees it (bounded_cgls.h): the unknowns a, residuals
/// [rImg; rLap; rId], gradient s, z = D² s and direction p, all on the GPU.
struct Solver::State final : BoundedLeastSquares {
    GpuDevice& device;
    Volume volume;
    Lighting lighting;
    std::vector<SolveView> views;
    SolveOptions opt;

    Int3 udims;
    size_t cells = 0, elements = 0;
    std::unique_ptr<GpuVolume> gpu;
    std::unique_ptr<Projector> W;
    std::unique_ptr<SparseCells> sparseCells;  ///< a sparse volume's unknown cells, for the Laplacian (else null)
    BrickLayout unknownBricks;  ///< a sparse volume's unknown grid (udims): stored voxels are the unknowns
    VectorOps ops;
    // The unknowns a, the previous iterate, gradient s and direction p; the image rows' data
    // (observations, √weights) and residual/work vectors; the Laplacian rows' residual and work.
    GpuVector a, aPrev, s, p, hull, obs, sqrtW, rImg, qImg, tmpImg, dImg, rLap, qLap, dLap, tmpU, rId;
    // The preconditioner D² (per unknown and channel) and the preconditioned gradient z = D² s.
    GpuVector precond, z;
    GpuVector rPrev;  ///< rImg before the step: what the step changed (SolveOptions::visibleChange)
    /// 1 where an unknown may move: the hull, or in a re-solve after a stroke the part of it the
    /// changed pixels see (solver_local.cpp). The gradient is masked with it.
    GpuVector movable;
    Bounds bounds;
    std::vector<BlockRegularizer> blocks;
    Vec3d constant{0, 0, 0};  // λ0‖a‖² + λ1‖a−1‖² = λ‖a−t‖² + λ0λ1/λ per element
    Vec3d weightSum{0, 0, 0};
    std::vector<Vec3d> viewWeightSum;
    std::vector<float> hullHost;
    std::vector<std::shared_ptr<const ViewRenders>> viewRenders;  ///< each view at the unknowns' bounds (reach.h), until the reach analysis
    std::vector<float> sqrtWHost;  ///< sqrtW as uploaded
    /// The observations and the raw weights (before normalization) as built, for the next solve's
    /// comparison (SolveCache::LastSolve), under this key.
    std::vector<float> obsHost, rawWeightHost;
    std::string lastKey;
    /// What the cache's keys take from the volume, hashed once per solve (buildObservations; with a cache).
    VolumeKey volumeKey;
    /// Per view, the squared residual of the pixels a re-solve after a stroke leaves untouched
    /// (they see no unknown that moves); added to each view's RMS. Empty: none.
    std::vector<Vec3d> viewUntouched;
    double untouchedObjective = 0;  ///< all of that and the untouched regularizer rows: the objective's part a re-solve cannot move
    SolveCache* cache = nullptr;   ///< parts kept between solves (solve_cache.h); may be null
    SolveReport report;

    State(GpuDevice& d, const Volume& v, const Lighting& l, std::vector<SolveView> vs, SolveOptions o)
        : device(d), volume(v), lighting(l), views(std::move(vs)), opt(std::move(o)), ops(d) {}

    // Set-up (solver_setup.cpp).
    void validateInputs();
    // Sparse volumes (solver_sparse.cpp).
    /// Activates the bricks the unknowns may reach beyond the volume's active ones: all 26 around
    /// each for extinction (the paint can grow the medium), those the hull reaches for emission
    /// and albedo (they act only inside the medium).
    void growApron();
    /// unknownBricks: the volume's own bricks at its resolution, else coarser ones over the
    /// active region; without a resolution, the finest whose vectors fit the GPU's storage blocks.
    void chooseSparseUnknowns();
    /// The unknowns' start values (4 floats each, block `block` of `init`) from a grid of the volume.
    void sparseUnknownsFrom(const std::vector<float>& grid, std::vector<float>& init, size_t block) const;
    /// A grid of the volume (3 floats per stored voxel) from block `block` of the unknowns.
    std::vector<float> sparseGridFrom(const std::vector<float>& unknowns, size_t block) const;
    /// The prior's values, 3 per element: as given, or (a sparse volume solved on coarser unknowns,
    /// given per stored voxel of the volume) at each unknown's centre. Throws InvalidArgument else.
    std::vector<float> priorOnUnknowns() const;
    /// Throws LimitExceeded when a vector of the unknowns or pixels is over the GPU's storage-block size.
    void checkVectorsFit() const;
    void allocate();
    /// Whether a block has a Laplacian term, or an identity one (l2, toward one, a prior): the
    /// vectors of a term that is off are never allocated (issue #40: 4 of 20 full-size vectors).
    bool usesLaplacian() const;
    bool usesIdentity() const;
    void buildObservations();
    void buildHull();
    void markHullFromExtinction();
    void markHullFromMasks(const std::vector<float>& o, const std::vector<float>& w);
    /// The views' rows of W (SolveOptions::rowCacheBytes) and, when all fit, vector work over
    /// the hull and the constrained pixels only.
    void cacheOperator();
    /// View v's rows from those work ahead wrote for its every pixel (nullptr: none kept, or not
    /// readable by the host): cut down to its weighted pixels `mask` and kept under `key` (its own
    /// rows' key), or those rows as they are (`asTheyAre`: the pixels left out have no entries).
    std::shared_ptr<const SparseRows> rowsMadeAhead(size_t v, int channels, const std::vector<uint8_t>& mask, const std::string& key,
                                                    bool& asTheyAre);
    /// Every vector operation (and W, Wᵀ) over these pixels and unknowns only (gpu_vector.h).
    void useSupports(std::shared_ptr<const Support> pixels, std::shared_ptr<const Support> voxels);
    void initialUnknowns();
    void buildRegularizers();
    void buildPreconditioner();
    /// Re-solve after a stroke (solver_local.cpp): when the last solve with the same settings left
    /// the volume this one starts from and few pixels changed, restricts the solve to the
    /// unknowns those pixels see and the pixels that see them.
    void restrictToStroke();
    /// Leaves this solve's observations (moved out: the solve is over) and result in the cache for the next one.
    /// `solveMs`: the solve's time, what the kept state can save a re-solve (SolveCache cost).
    void rememberSolve(const Volume& result, double solveMs);
    /// Coarse to fine: solves opt.coarseIterations on half the resolution and starts from it.
    void warmStartFromCoarse(const std::atomic<bool>* cancel);
    Volume result();

    // The operator and residuals (solver.cpp).
    void applyA(const GpuVector& x, GpuVector& img, GpuVector& lap);  // [img; lap] = A x (identity rows implicit)
    void applyLaplacian(const GpuVector& x, GpuVector& lap);          // lap = the Laplacian rows of A x
    /// Moves a by step·x with residuals [rImg; rLap; rId] updated by the matching A x = [img; lap].
    void move(const Vec3d& step, const GpuVector& x, const GpuVector& img, const GpuVector& lap);
    void applyAt();  // s from rImg, rLap, rId
    Vec3d precondition();  // z = D² s; returns s·z (γ of preconditioned CGLS)
    /// [rImg; rLap; rId] = b − A a, from scratch, over the vectors' supports. W a is skipped while
    /// startsAtZero (it is 0 exactly: issue #40, one W fewer in a first solve from nothing).
    void computeResiduals();
    bool startsAtZero = false;  ///< a is the all-zero start (initialUnknowns) and has not moved yet
    double totalObjective();
    std::vector<double> rmsPerView();

    // Bounded CGLS's operations (bounded_cgls.h) on the GPU vectors (solver.cpp).
    Vec3d restart() override;
    Vec3d gradient() override;
    Vec3d curvature() override;  // q = [qImg; qLap] = A p
    Vec3d stepToBound() override;
    void move(const Vec3d& t) override { move(t, p, qImg, qLap); }
    void moveProjected(const Vec3d& alpha) override;  // d = [tmpU], A d = [dImg; dLap]
    void undoProjected(const Vec3d& undo) override { move(-undo, tmpU, dImg, dLap); }
    void clampToBounds() override { ops.clamp(a, bounds); }
    Vec3d objective() override;
    Vec3d slope() override { return ops.dot(p, s); }
    void conjugate(const Vec3d& beta, bool freeOnly) override;
    void keepIterate() override { ops.copy(a, aPrev); }
    void restoreIterate() override { ops.copy(aPrev, a); }
    CglsSettings cglsSettings() const;

    /// Adds the iteration to the report and returns its progress (with this iteration's times).
    SolveProgress recordIteration(int iteration, double objective, Clock::time_point start,
                                  Clock::time_point iterationStart, const ProjectorStats& before);
};

}  // namespace volstyle::core

// The solver's iterations (TVCG Sec. 5.1, SPEC §2): bounded CGLS on the stacked system, three
// channels in lockstep, every vector on the GPU. Set-up lives in solver_setup.cpp.
#include "core/solve/solver.h"

#include "core/solve/reach.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <optional>
#include <utility>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/solve/solver_state.h"

namespace volstyle::core {
namespace {

/// The recurrences' residuals drift in float32; every this many iterations they are recomputed
/// from the unknowns (a CGLS restart).
constexpr int kRestartEvery = 25;
/// An iteration whose relative decrease is at most this counts as no decrease ...
constexpr double kFlatDecrease = 1e-12;
/// ... and this many in a row stop the solve as stagnated.
constexpr int kFlatIterationsToStop = 3;
/// Iterations in a row (not cut short at the first bound) that change no pixel visibly before the
/// solve stops as settled.
constexpr int kSettledIterationsToStop = 2;
/// A re-solve after a stroke stops once an iteration gains less than this fraction of what the
/// re-solve has gained so far (measured on issue #12's stroke: the painted view's RMS is then
/// within 4% of where 30 iterations take it).
constexpr double kStrokeGain = 0.01;
/// Guards the relative decrease against a zero objective.
constexpr double kTinyObjective = 1e-300;

double sum(const Vec3d& v) { return v.x + v.y + v.z; }

}  // namespace

void Solver::State::applyA(const GpuVector& x, GpuVector& img, GpuVector& lap) {
    W->forward(x, img);
    ops.multiply(sqrtW, img);
    applyLaplacian(x, lap);
}

void Solver::State::applyLaplacian(const GpuVector& x, GpuVector& lap) {
    for (const auto& b : blocks)
        if (b.cLap > 0) ops.laplacian(b.cLap, x, hull, udims, lap, b.range, sparseCells.get());  // blocks without stay 0
}

void Solver::State::move(const Vec3d& step, const GpuVector& x, const GpuVector& img, const GpuVector& lap) {
    ops.axpy(step, x, a);
    ops.axpy(-step, img, rImg);
    if (rLap.size() > 0) ops.axpy(-step, lap, rLap);
    for (const auto& b : blocks)
        if (b.cId > 0) ops.axpy(-step * b.cId, x, rId, b.range);
}

void Solver::State::applyAt() {
    ops.copy(rImg, tmpImg);
    ops.multiply(sqrtW, tmpImg);
    W->adjoint(tmpImg, s);
    for (const auto& b : blocks) {
        if (b.cLap > 0) {
            ops.laplacian(b.cLap, rLap, hull, udims, tmpU, b.range, sparseCells.get());  // L is symmetric
            ops.axpy(Vec3d(1.0), tmpU, s, b.range);
        }
        if (b.cId > 0) ops.axpy(Vec3d(b.cId), rId, s, b.range);
    }
    ops.multiply(movable, s);
    if (opt.enforceBounds) ops.freeSet(a, s, bounds);
}

Vec3d Solver::State::restart() {
    computeResiduals();  // from scratch: also clears the drift of the recurrences
    const Vec3d gamma = gradient();
    ops.copy(z, p);
    return gamma;
}

Vec3d Solver::State::gradient() {
    applyAt();
    return precondition();
}

CglsSettings Solver::State::cglsSettings() const {
    CglsSettings settings;
    settings.enforceBounds = opt.enforceBounds;
    settings.projected = opt.boundsMethod == BoundsMethod::Projected;
    settings.restartEvery = kRestartEvery;
    return settings;
}

void Solver::State::computeResiduals() {
    ops.copy(obs, rImg);
    if (!std::exchange(startsAtZero, false)) {  // only the first call can find a still at its start
        W->forward(a, qImg);
        ops.axpy(Vec3d(-1.0), qImg, rImg);
    }
    ops.multiply(sqrtW, rImg);
    if (rLap.size() > 0) rLap.fill(0.0f);
    if (rId.size() > 0) rId.fill(0.0f);
    std::vector<float> av, r;
    for (const auto& b : blocks) {
        if (b.cLap > 0) ops.laplacian(-b.cLap, a, hull, udims, rLap, b.range, sparseCells.get());
        if (b.cId <= 0) continue;
        if (av.empty()) av = a.download(), r.assign(av.size(), 0.0f);
        for (size_t i = 4 * b.range.first; i < 4 * (b.range.first + b.range.count); ++i)
            if (i % 4 != 3 && hullHost[i - i % 4] > 0)
                r[i] = float(b.cId * ((b.targets.empty() ? b.target : b.targets[i - 4 * b.range.first]) - av[i]));
    }
    if (!r.empty()) rId.upload(r);
}

Vec3d Solver::State::precondition() {
    ops.copy(s, z);
    ops.multiply(precond, z);
    return ops.dot(s, z);
}

Vec3d Solver::State::objective() {
    Vec3d f = ops.dot(rImg, rImg) + constant;
    bool lap = false, id = false;
    for (const auto& b : blocks) lap |= b.cLap > 0, id |= b.cId > 0;
    if (lap) f += ops.dot(rLap, rLap);
    if (id) f += ops.dot(rId, rId);
    return f;
}

double Solver::State::totalObjective() { return sum(objective()); }

std::vector<double> Solver::State::rmsPerView() {
    std::vector<Range> ranges;
    for (size_t v = 0; v < views.size(); ++v) ranges.push_back(W->viewRange(v));
    const std::vector<Vec3d> dots = ops.dots(rImg, rImg, ranges);  // one dispatch for every view (issue #40)
    std::vector<double> out;
    for (size_t v = 0; v < views.size(); ++v) {
        Vec3d r2 = dots[v];
        if (!viewUntouched.empty()) r2 += viewUntouched[v];
        out.push_back(viewRms(r2, weightSum, viewWeightSum[v]));
    }
    return out;
}

Vec3d Solver::State::curvature() {
    applyA(p, qImg, qLap);
    Vec3d delta = ops.dot(qImg, qImg);
    for (const auto& b : blocks) {
        if (b.cLap > 0) delta += ops.dot(qLap, qLap, b.range);
        if (b.cId > 0) delta += ops.dot(p, p, b.range) * (b.cId * b.cId);
    }
    return delta;
}

Vec3d Solver::State::stepToBound() { return ops.maxStep(a, p, bounds); }

void Solver::State::moveProjected(const Vec3d& alpha) {
    // a' = clamp(a + αp) from a = aPrev; its residual needs A (a' − a), one more projection.
    ops.axpy(alpha, p, a);
    const bool byColumns = W->canForwardByColumns();
    if (byColumns) ops.copy(a, z);  // z is free until the next direction: a + αp before the clamp
    ops.clamp(a, bounds);
    tmpU.fill(0.0f);  // d = a' − a, 0 off the vectors' support too
    ops.axpy(Vec3d(1.0), a, tmpU);
    ops.axpy(Vec3d(-1.0), aPrev, tmpU);
    ops.copy(aPrev, a);
    if (byColumns) {
        // A d = α A p + A c with c = a' − (a + αp), exactly 0 wherever no bound clamped: A p is
        // qImg already, and A c reads only the clamped unknowns' columns (one forward saved).
        ops.xpby(a, Vec3d(-1.0), z);  // a is back at aPrev: z = aPrev − (a + αp) ...
        ops.axpy(Vec3d(1.0), tmpU, z);  // ... + d = a' − (a + αp)
        W->forwardByColumns(z, dImg);
        ops.multiply(sqrtW, dImg);
        ops.axpy(alpha, qImg, dImg);
        applyLaplacian(tmpU, dLap);
    } else {
        applyA(tmpU, dImg, dLap);
    }
    move(Vec3d(1.0), tmpU, dImg, dLap);
}

void Solver::State::conjugate(const Vec3d& beta, bool freeOnly) {
    ops.xpby(z, beta, p);  // p = D² s + β p: preconditioned CGLS
    if (freeOnly) ops.freeSet(a, p, bounds);
}

SolveProgress Solver::State::recordIteration(int iteration, double objective, Clock::time_point start,
                                             Clock::time_point iterationStart, const ProjectorStats& before) {
    report.iterations = iteration;
    report.objectiveHistory.push_back(objective);
    report.finalRms = rmsPerView();
    const ProjectorStats& after = W->stats();
    SolveProgress pr;
    pr.iteration = iteration;
    pr.objective = objective;
    pr.rmsPerView = report.finalRms;
    pr.elapsedMs = msSince(start);
    pr.forwardMs = after.forwardMs - before.forwardMs;
    pr.adjointMs = after.adjointMs - before.adjointMs;
    pr.vectorMs = std::max(0.0, msSince(iterationStart) - pr.forwardMs - pr.adjointMs);
    report.forwardMs += pr.forwardMs, report.adjointMs += pr.adjointMs, report.vectorMs += pr.vectorMs;
    return pr;
}

Volume Solver::currentVolume() { return m_state->result(); }

namespace {

/// The stopping rules after an iteration from objective f to fNew: relative decrease below the
/// tolerance (unless a bound cut the step short), or no decrease several times in a row. A
/// re-solve after a stroke (`strokeStart`: its first objective) also stops once an iteration
/// gains less than kStrokeGain of what the re-solve has gained so far: its objective is mostly
/// the error of pixels it cannot move, so a decrease relative to it says little. Tolerance 0
/// runs every iteration, as for any solve.
StopReason stopTest(double f, double fNew, bool cutShort, double tolerance, int& flat, std::optional<double> strokeStart) {
    const double decrease = (f - fNew) / std::max(f, kTinyObjective);
    flat = decrease <= kFlatDecrease ? flat + 1 : 0;
    if (flat >= kFlatIterationsToStop) return StopReason::Stagnated;
    if (cutShort || decrease < 0) return StopReason::None;
    if (decrease < tolerance) return StopReason::Converged;
    if (strokeStart && tolerance > 0 && f - fNew < kStrokeGain * (*strokeStart - fNew)) return StopReason::Converged;
    return StopReason::None;
}

}  // namespace

SolveResult Solver::run(const ProgressCallback& progress, const std::atomic<bool>* cancel) {
    State& st = *m_state;
    SolveReport& rep = st.report;
    const auto t0 = Clock::now();
    if (rep.constraintPixels == 0 || rep.hullCount == 0) {
        rep.stopReason = rep.constraintPixels == 0 ? StopReason::NoConstraints : StopReason::EmptyHull;
        spdlog::warn("solve: nothing to solve ({})", stopReasonName(rep.stopReason));
        return {st.volume, rep};
    }
    // What the bounds leave out of reach, from the renders of the start: after the first
    // iteration, so a person sees progress at once rather than after the analysis' renders.
    bool reachPending = st.opt.analyzeReach;
    auto analyseReach = [&](SolveProgress last) {
        reachPending = false;
        if (progress) {
            last.phase = SolvePhase::AnalysingReach;
            progress(last);
        }
        const auto tReach = Clock::now();
        analyzeReach(st.viewRenders, st.views, st.opt, rep);
        rep.reach.ms = msSince(tReach);
        if (!rep.reach.advice.empty()) spdlog::info("solve: {}", rep.reach.advice);
        st.viewRenders.clear();
        st.viewRenders.shrink_to_fit();
    };
    if (!reachPending) {
        st.viewRenders.clear();
        st.viewRenders.shrink_to_fit();
    }
    if (st.opt.coarseIterations > 0 && !rep.local.active) {  // a re-solve starts where it is
        st.warmStartFromCoarse(cancel);
        rep.setupPhases.emplace_back("coarse start", msSince(t0));
    }
    const auto tStart = Clock::now();
    BoundedCgls cgls(st, st.cglsSettings());
    cgls.start();
    double f = st.totalObjective();
    rep.initialObjective = f;
    rep.objectiveHistory.push_back(f);
    rep.initialRms = st.rmsPerView();
    rep.finalRms = rep.initialRms;
    rep.setupPhases.emplace_back("first residual", msSince(tStart));
    int flat = 0, settled = 0;

    for (int it = 1; it <= st.opt.maxIterations && rep.stopReason == StopReason::None; ++it) {
        if (cancel && cancel->load()) throw Cancelled("solve cancelled after " + std::to_string(it - 1) + " iterations");
        const auto tIt = Clock::now();
        const ProjectorStats before = st.W->stats();
        if (cgls.zeroGradient()) {
            rep.stopReason = StopReason::ZeroGradient;
            break;
        }
        // Radiance only: an extinction solve's residuals are optical depths.
        const bool watchChange = st.opt.visibleChange > 0 && st.opt.unknown != Unknown::Extinction;
        if (watchChange) st.ops.copy(st.rImg, st.rPrev);
        const CglsStep step = cgls.iterate(it);
        if (!step.finite) {  // the iterate is the last finite one again
            rep.stopReason = StopReason::NumericalBreakdown;
            spdlog::warn("solve: objective became non-finite at iteration {}; keeping iteration {}", it, it - 1);
            break;
        }
        const double fNew = sum(step.objective);
        const bool cutShort = step.cutShort;

        const SolveProgress pr = st.recordIteration(it, fNew, t0, tIt, before);
        if (progress) progress(pr);
        if (reachPending) analyseReach(pr);

        // A re-solve measures its decrease against the part of the objective it can move.
        const double fixed = st.untouchedObjective;
        rep.stopReason = stopTest(f - fixed, fNew - fixed, cutShort, st.opt.tolerance, flat,
                                  rep.local.active ? std::optional<double>(rep.initialObjective - fixed) : std::nullopt);
        if (watchChange && rep.stopReason == StopReason::None) {
            // The largest change of any constrained pixel: (r_prev − r)/√w = W Δa at that pixel.
            const double change = maxComponent(st.ops.maxChange(st.rPrev, st.rImg, st.sqrtW));
            // A step cut short at the first bound can be tiny while the next free one is not: it
            // neither counts nor resets. Projected steps move every variable they can.
            if (change >= st.opt.visibleChange) settled = 0;
            else if (!cutShort) ++settled;
            if (settled >= kSettledIterationsToStop) rep.stopReason = StopReason::Settled;
        }
        f = fNew;
    }
    if (reachPending) {  // no iteration ran (a zero gradient at the start)
        SolveProgress none;
        none.objective = f;
        analyseReach(none);
    }
    if (rep.stopReason == StopReason::None) rep.stopReason = StopReason::MaxIterations;
    rep.finalObjective = rep.objectiveHistory.back();
    Volume out = st.result();
    st.rememberSolve(out, msSince(t0));
    rep.totalMs = msSince(t0);
    return {std::move(out), rep};
}

}  // namespace volstyle::core


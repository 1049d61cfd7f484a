// The solver's iterations (TVCG Sec. 5.1, SPEC §2): bounded CGLS on the stacked system, three
// channels in lockstep, every vector on the GPU. Set-up lives in solver_setup.cpp.
#include "core/solve/solver.h"

#include "core/solve/reach.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <optional>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/solve/solver_state.h"

namespace volstyle::core {
namespace {

/// The recurrences' residuals drift in float32; every this many iterations they are recomputed
/// from the unknowns (a CGLS restart).
constexpr int kRestartEvery = 25;
/// A carried-over direction is kept while p·s ≥ this fraction of ‖s‖² (a clear descent direction);
/// below it, that channel restarts from its gradient.
constexpr double kMinDescentFraction = 0.2;
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
        if (b.cLap > 0) ops.laplacian(b.cLap, x, hull, udims, lap, b.range);  // blocks without stay 0
}

void Solver::State::move(const Vec3d& step, const GpuVector& x, const GpuVector& img, const GpuVector& lap) {
    ops.axpy(step, x, a);
    ops.axpy(-step, img, rImg);
    ops.axpy(-step, lap, rLap);
    for (const auto& b : blocks)
        if (b.cId > 0) ops.axpy(-step * b.cId, x, rId, b.range);
}

void Solver::State::applyAt() {
    ops.copy(rImg, tmpImg);
    ops.multiply(sqrtW, tmpImg);
    W->adjoint(tmpImg, s);
    for (const auto& b : blocks) {
        if (b.cLap > 0) {
            ops.laplacian(b.cLap, rLap, hull, udims, tmpU, b.range);  // L is symmetric
            ops.axpy(Vec3d(1.0), tmpU, s, b.range);
        }
        if (b.cId > 0) ops.axpy(Vec3d(b.cId), rId, s, b.range);
    }
    ops.multiply(movable, s);
    if (opt.enforceBounds) ops.freeSet(a, s, bounds);
}

void Solver::State::restart(Vec3d& gamma) {
    computeResiduals();  // from scratch: also clears the drift of the recurrences
    applyAt();
    gamma = precondition();
    ops.copy(z, p);
}

void Solver::State::computeResiduals() {
    W->forward(a, qImg);
    ops.copy(obs, rImg);
    ops.axpy(Vec3d(-1.0), qImg, rImg);
    ops.multiply(sqrtW, rImg);
    rLap.fill(0.0f);
    rId.fill(0.0f);
    std::vector<float> av, r;
    for (const auto& b : blocks) {
        if (b.cLap > 0) ops.laplacian(-b.cLap, a, hull, udims, rLap, b.range);
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
    std::vector<double> out;
    for (size_t v = 0; v < views.size(); ++v) {
        Vec3d r2 = ops.dot(rImg, rImg, W->viewRange(v));
        if (!viewUntouched.empty()) r2 += viewUntouched[v];
        out.push_back(viewRms(r2, weightSum, viewWeightSum[v]));
    }
    return out;
}

StepLength Solver::State::stepLength(const Vec3d& slope) {
    // Along p: α = p·s / ‖A p‖² (the exact line minimum), cut where a bound is met.
    applyA(p, qImg, qLap);
    Vec3d delta = ops.dot(qImg, qImg);
    for (const auto& b : blocks) {
        if (b.cLap > 0) delta += ops.dot(qLap, qLap, b.range);
        if (b.cId > 0) delta += ops.dot(p, p, b.range) * (b.cId * b.cId);
    }
    StepLength step;
    if (opt.enforceBounds) step.toBound = ops.maxStep(a, p, bounds);
    for (int c = 0; c < 3; ++c) {
        step.alpha[c] = delta[c] > 0 && slope[c] > 0 ? slope[c] / delta[c] : 0.0;
        step.hit[c] = step.toBound[c] < step.alpha[c];
    }
    return step;
}

bool Solver::State::takeStep(const StepLength& step) {
    ops.copy(a, aPrev);
    if (!step.anyHit()) {
        move(step.alpha, p, qImg, qLap);
        return false;
    }
    if (opt.boundsMethod == BoundsMethod::Projected) return projectedStep(step);
    Vec3d cut;
    for (int c = 0; c < 3; ++c) cut[c] = step.hit[c] ? step.toBound[c] : step.alpha[c];
    move(cut, p, qImg, qLap);
    ops.clamp(a, bounds);  // rounding only
    return true;
}

bool Solver::State::projectedStep(const StepLength& step) {
    // The step leaves the box in some channel. Try the projected step a' = clamp(a + αp): it moves
    // many variables at once (in channels that stay inside it is the plain CG step). Its residual
    // needs A (a' − a), one more projection. Channels where a' lowers the objective keep it; the
    // others take the step cut at the first bound, which always lowers it.
    const Vec3d fBefore = objective();
    ops.axpy(step.alpha, p, a);
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
        ops.axpy(step.alpha, qImg, dImg);
        applyLaplacian(tmpU, dLap);
    } else {
        applyA(tmpU, dImg, dLap);
    }
    move(Vec3d(1.0), tmpU, dImg, dLap);
    const Vec3d fProjected = objective();
    Vec3d undo(0.0), cut(0.0);
    for (int c = 0; c < 3; ++c) {
        if (!step.hit[c] || fProjected[c] <= fBefore[c]) continue;
        undo[c] = -1.0;  // reject the projected step in this channel
        cut[c] = step.toBound[c];
    }
    const bool rejected = maxComponent(-undo) > 0;
    if (rejected) {
        move(undo, tmpU, dImg, dLap);
        move(cut, p, qImg, qLap);
    }
    ops.clamp(a, bounds);  // rounding only: every move above stays inside
    return rejected;
}

Vec3d Solver::State::nextDirection(int iteration, const Vec3d& gamma, Vec3d& slope) {
    // New gradient and direction. Plain CGLS sets β = γ'/γ. When the free set changes the old
    // direction is no longer conjugate; keep β only while p stays a clear descent direction, else
    // restart that channel from its gradient. Steps use the exact line minimum p·s / ‖A p‖², so
    // every step lowers the objective.
    Vec3d gammaNew;
    if (iteration % kRestartEvery == 0) {
        restart(gammaNew);  // refreshes the recurrences' residuals from scratch
        slope = gammaNew;
        return gammaNew;
    }
    applyAt();
    gammaNew = precondition();
    const Vec3d ps = ops.dot(p, s);
    Vec3d beta;
    for (int c = 0; c < 3; ++c) {
        beta[c] = gamma[c] > 0 ? gammaNew[c] / gamma[c] : 0.0;
        if (gammaNew[c] + beta[c] * ps[c] < kMinDescentFraction * gammaNew[c]) beta[c] = 0.0;
        slope[c] = gammaNew[c] + beta[c] * ps[c];
    }
    ops.xpby(z, beta, p);  // p = D² s + β p: preconditioned CGLS
    if (opt.enforceBounds) {
        // β p can still push a variable that sits at its bound outward: the step would stop at
        // once (or project it back). Dropping those components keeps p a descent direction (s is
        // 0 there, or points inward, so p·s only grows) and lets the step go its full length.
        // On the CT slice of bench/solver_race: 4.3e-6 -> 6e-7 of the start after 100 iterations.
        ops.freeSet(a, p, bounds);
        slope = ops.dot(p, s);
    }
    return gammaNew;
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
    if (st.opt.analyzeReach) {
        const auto tReach = Clock::now();
        analyzeReach(st.viewRenders, st.views, st.opt, rep);  // what the bounds leave out of reach
        rep.reach.ms = msSince(tReach);
        if (!rep.reach.advice.empty()) spdlog::info("solve: {}", rep.reach.advice);
    }
    st.viewRenders.clear();
    st.viewRenders.shrink_to_fit();
    if (st.opt.coarseIterations > 0 && !rep.local.active) st.warmStartFromCoarse(cancel);  // a re-solve starts where it is
    Vec3d gamma;  // s·D²s, s = Aᵀr restricted to the free variables (‖s‖² unpreconditioned)
    st.restart(gamma);
    Vec3d slope = gamma;  // p·s: the objective's descent rate along p (= γ in plain CGLS)
    double f = st.totalObjective();
    rep.initialObjective = f;
    rep.objectiveHistory.push_back(f);
    rep.initialRms = st.rmsPerView();
    rep.finalRms = rep.initialRms;
    int flat = 0, settled = 0;

    for (int it = 1; it <= st.opt.maxIterations && rep.stopReason == StopReason::None; ++it) {
        if (cancel && cancel->load()) throw Cancelled("solve cancelled after " + std::to_string(it - 1) + " iterations");
        const auto tIt = Clock::now();
        const ProjectorStats before = st.W->stats();
        if (gamma.x <= 0 && gamma.y <= 0 && gamma.z <= 0) {
            rep.stopReason = StopReason::ZeroGradient;
            break;
        }
        const StepLength step = st.stepLength(slope);
        // Radiance only: an extinction solve's residuals are optical depths.
        const bool watchChange = st.opt.visibleChange > 0 && st.opt.unknown != Unknown::Extinction;
        if (watchChange) st.ops.copy(st.rImg, st.rPrev);
        const bool cutShort = st.takeStep(step);
        const double fNew = st.totalObjective();
        if (!std::isfinite(fNew)) {
            st.ops.copy(st.aPrev, st.a);  // keep the last finite iterate
            rep.stopReason = StopReason::NumericalBreakdown;
            spdlog::warn("solve: objective became non-finite at iteration {}; keeping iteration {}", it, it - 1);
            break;
        }
        gamma = st.nextDirection(it, gamma, slope);

        const SolveProgress pr = st.recordIteration(it, fNew, t0, tIt, before);
        if (progress) progress(pr);

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
    if (rep.stopReason == StopReason::None) rep.stopReason = StopReason::MaxIterations;
    rep.finalObjective = rep.objectiveHistory.back();
    Volume out = st.result();
    st.rememberSolve(out);
    rep.totalMs = msSince(t0);
    return {std::move(out), rep};
}

}  // namespace volstyle::core


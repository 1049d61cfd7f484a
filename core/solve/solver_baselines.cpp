// The reference methods benchmarks race the solver against (solver.h, BaselineMethod): Adam, as a
// differentiable-rendering solver would take, and SART, the tomography textbook's method, both
// over the solver's own set-up so that they see exactly its operators, observations and bounds.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/solve/solver_state.h"

namespace volstyle::core {
namespace {

constexpr double kAdamBeta1 = 0.9, kAdamBeta2 = 0.999, kAdamEpsilon = 1e-8;

/// 1/x per channel where x > 0, else 0 (rows or columns no ray weights).
std::vector<float> reciprocal(std::vector<float> v) {
    for (size_t i = 0; i < v.size(); ++i) v[i] = i % 4 != 3 && v[i] > 0 ? 1.0f / v[i] : 0.0f;
    return v;
}

/// The views in an order that keeps consecutive ones far apart (a stride near n/φ, coprime with
/// n): SART converges much faster than in camera order when neighbouring views are alike.
std::vector<size_t> spreadOrder(size_t n) {
    size_t stride = std::max<size_t>(1, size_t(std::lround(double(n) * 0.618)));
    while (std::gcd(stride, n) != 1) ++stride;
    std::vector<size_t> order;
    for (size_t k = 0; k < n; ++k) order.push_back(k * stride % n);
    return order;
}

}  // namespace

SolveResult Solver::runBaseline(BaselineMethod method, int iterations, double rate, const ProgressCallback& progress) {
    State& st = *m_state;
    for (const auto& b : st.blocks)
        if (b.cLap > 0 || b.cId > 0) throw InvalidArgument("baseline methods solve the data term only: set the regularization to 0");
    SolveReport& rep = st.report;
    if (rep.local.active)
        throw InvalidArgument("baseline methods solve the whole problem: build the solver without a cache or with local_resolve off");
    st.viewRenders.clear();
    const auto t0 = Clock::now();
    auto measure = [&] {
        st.computeResiduals();
        return st.totalObjective();
    };
    rep.initialObjective = measure();
    rep.objectiveHistory.push_back(rep.initialObjective);
    rep.initialRms = rep.finalRms = st.rmsPerView();

    // Adam's moments (host: the update is a few flops per unknown next to W and Wᵀ).
    std::vector<float> m1, m2;
    // SART's normalizations: the rows' sums of diag(√w) W over the hull, each view's columns' sums.
    GpuVector invRowSum, weightedObs;
    std::vector<GpuVector> invColumnSum;
    if (method == BaselineMethod::Sart) {
        st.ops.copy(st.hull, st.tmpU);
        st.W->forward(st.tmpU, st.tmpImg);
        st.ops.multiply(st.sqrtW, st.tmpImg);
        invRowSum = GpuVector(st.W->pixelCount(), "sart-rows");
        invRowSum.upload(reciprocal(st.tmpImg.download()));
        for (size_t v = 0; v < st.views.size(); ++v) {
            st.W->adjointView(v, st.sqrtW, st.tmpU);
            invColumnSum.emplace_back(st.elements, "sart-columns");
            std::vector<float> columns = reciprocal(st.tmpU.download());
            for (size_t i = 0; i < columns.size(); ++i) columns[i] *= st.hullHost[i];  // as CGLS: the hull only
            invColumnSum.back().upload(columns);
        }
        weightedObs = GpuVector(st.W->pixelCount(), "sart-obs");
        st.ops.copy(st.obs, weightedObs);
        st.ops.multiply(st.sqrtW, weightedObs);
    }
    const std::vector<size_t> order = spreadOrder(st.views.size());

    for (int it = 1; it <= iterations; ++it) {
        const auto tIt = Clock::now();
        const ProjectorStats before = st.W->stats();
        if (method == BaselineMethod::Adam) {
            st.applyAt();  // s = Aᵀ r = −gradient/2 over the free set (rImg from the last measure)
            const std::vector<float> s = st.s.download();
            std::vector<float> a = st.a.download();
            if (m1.empty()) m1.assign(a.size(), 0.0f), m2.assign(a.size(), 0.0f);
            const double c1 = 1 - std::pow(kAdamBeta1, it), c2 = 1 - std::pow(kAdamBeta2, it);
            for (size_t i = 0; i < a.size(); ++i) {
                if (i % 4 == 3 || st.hullHost[i - i % 4] <= 0) continue;
                const double g = -double(s[i]);
                m1[i] = float(kAdamBeta1 * m1[i] + (1 - kAdamBeta1) * g);
                m2[i] = float(kAdamBeta2 * m2[i] + (1 - kAdamBeta2) * g * g);
                const size_t block = (i / 4) / st.bounds.blockSize;
                const double next = a[i] - rate * (m1[i] / c1) / (std::sqrt(m2[i] / c2) + kAdamEpsilon);
                a[i] = float(std::clamp(next, double(st.bounds.lower[block]), double(st.bounds.upper[block])));
            }
            st.a.upload(a);
        } else {
            for (size_t v : order) {
                const Range pixels = st.W->viewRange(v);
                st.W->forwardView(v, st.a, st.qImg);
                st.ops.multiply(st.sqrtW, st.qImg, pixels);
                st.ops.copy(weightedObs, st.tmpImg);
                st.ops.axpy(Vec3d(-1.0), st.qImg, st.tmpImg, pixels);  // b_v − A_v a
                st.ops.multiply(invRowSum, st.tmpImg, pixels);
                st.ops.multiply(st.sqrtW, st.tmpImg, pixels);  // A_vᵀ = W_vᵀ diag(√w)
                st.W->adjointView(v, st.tmpImg, st.s);
                st.ops.multiply(invColumnSum[v], st.s);
                st.ops.axpy(Vec3d(rate), st.s, st.a);
                st.ops.clamp(st.a, st.bounds);
            }
        }
        const double f = measure();
        const SolveProgress pr = st.recordIteration(it, f, t0, tIt, before);
        if (progress) progress(pr);
        if (!std::isfinite(f)) {
            rep.stopReason = StopReason::NumericalBreakdown;
            break;
        }
    }
    if (rep.stopReason == StopReason::None) rep.stopReason = StopReason::MaxIterations;
    rep.finalObjective = rep.objectiveHistory.back();
    rep.totalMs = msSince(t0);
    return {st.result(), rep};
}

}  // namespace volstyle::core

// The solver's set-up (TVCG Sec. 4.2, 5.1–5.2): validated inputs, the observations and weights of
// every pixel, the bounds, the regularizer rows and the warm start (the hull of unknowns that can
// matter is solver_hull.cpp). Everything is built once, before the first iteration.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/solve/solve_cache.h"
#include "core/solve/solve_prefetch.h"
#include "core/solve/solver_state.h"
#include "core/volume/resample.h"

namespace volstyle::core {
namespace {

/// Extinction solves divide by L_bg − L_m: below this the pixel carries no information.
constexpr double kMinRadianceContrast = 1e-6;
/// An upper bound that means "none" in float vectors.
constexpr float kUnbounded = 3e38f;

std::string describeView(const SolveView& v) { return "view '" + v.name + "'"; }

/// One channel of one pixel: the observation o and its weight w.
struct Observation {
    double value = 0, weight = 0;
};

/// Extinction (TVCG Sec. 4.2.4): o = −ln((L − L_m) / (L_bg − L_m)) from the target L, the
/// background seen through the empty box L_bg and the medium radiance L_m. A ratio that is not
/// positive carries no information (weight 0); one above 1 is clamped to 1 (o = 0).
Observation observeTransmittance(double target, double background, double medium, double weight, SolveReport& report) {
    const double denom = background - medium;
    double ratio = std::abs(denom) < kMinRadianceContrast ? -1 : (target - medium) / denom;
    if (weight > 0 && !(ratio > 0)) {
        report.ignoredPixels++;
        return {0, 0};
    }
    if (weight > 0 && ratio > 1) {
        ratio = 1;
        report.clampedPixels++;
    }
    return {weight > 0 ? -std::log(ratio) : 0, weight};
}

}  // namespace

Solver::Solver(GpuDevice& device, const Volume& volume, const Lighting& lighting, std::vector<SolveView> views,
               SolveOptions options, SolveCache* cache)
    : m_state(std::make_unique<State>(device, volume, lighting, std::move(views), std::move(options))) {
    State& st = *m_state;
    st.cache = cache;
    // Each phase timed: the set-up is most of what a person waits for on a first solve (issue #40).
    auto phase = [&st, t = Clock::now()](const char* name) mutable {
        st.device.finish();
        st.report.setupPhases.emplace_back(name, msSince(t));
        t = Clock::now();
    };
    st.validateInputs();
    st.udims = st.opt.resolution.value_or(st.volume.dims());
    if (st.volume.isSparse()) {
        st.growApron();
        st.chooseSparseUnknowns();
    }
    st.cells = st.volume.isSparse() ? st.unknownBricks.storedVoxels() : size_t(st.udims.volume());
    st.elements = st.cells * (st.opt.unknown == Unknown::EmissionAlbedo ? 2 : 1);
    st.checkVectorsFit();
    st.gpu = std::make_unique<GpuVolume>(st.volume);
    st.W = std::make_unique<Projector>(device, *st.gpu, st.lighting, st.opt.unknown, st.opt.basis, st.udims,
                                       st.opt.stepVoxels, st.opt.exactTraversal);
    if (st.opt.mergeViewRows) st.W->setMergeViews(*st.opt.mergeViewRows);
    if (st.volume.isSparse()) {
        st.sparseCells = std::make_unique<SparseCells>(st.unknownBricks);
        st.W->useSparseUnknowns(st.unknownBricks);
    }
    for (const auto& v : st.views) st.W->addView(v.camera);
    phase("upload and views");
    st.allocate();
    phase("vectors");
    st.buildObservations();
    phase("renders and observations");
    st.buildHull();
    phase("hull");
    st.cacheOperator();
    phase("rows");
    st.initialUnknowns();
    st.buildRegularizers();
    st.restrictToStroke();
    phase("start and regularizers");
    st.buildPreconditioner();
    phase("preconditioner");
}

Solver::~Solver() = default;

void Solver::State::validateInputs() {
    opt.validate();
    volume.validate();
    lighting.validate();
    // Keep the requested views (all with a target by default).
    std::vector<SolveView> chosen;
    const std::set<std::string> requested(opt.views.begin(), opt.views.end());
    std::set<std::string> missing = requested;
    for (auto& v : views) {
        if (!requested.empty() && !requested.count(v.name)) continue;  // "views": only these
        missing.erase(v.name);
        if (v.target.empty()) {
            if (!opt.views.empty()) throw InvalidArgument(describeView(v) + " has no target");
            continue;
        }
        chosen.push_back(std::move(v));
    }
    if (!missing.empty()) throw InvalidArgument("solve options: views: no view named '" + *missing.begin() + "'");
    if (chosen.empty()) throw InvalidArgument("solve: no view has a target image; upload a painted target first");
    for (const auto& v : chosen) v.validate();
    views = std::move(chosen);
}

bool Solver::State::usesLaplacian() const {
    for (Unknown u : opt.unknown == Unknown::EmissionAlbedo ? std::vector{Unknown::Emission, Unknown::Albedo} : std::vector{opt.unknown})
        if (opt.regularizationFor(u).laplacian > 0) return true;
    return false;
}

bool Solver::State::usesIdentity() const {
    if (opt.prior.values && opt.prior.weight > 0) return true;
    for (Unknown u : opt.unknown == Unknown::EmissionAlbedo ? std::vector{Unknown::Emission, Unknown::Albedo} : std::vector{opt.unknown})
        if (opt.regularizationFor(u).l2 + opt.regularizationFor(u).towardOne > 0) return true;
    return false;
}

void Solver::State::allocate() {
    const size_t P = W->pixelCount(), E = elements;
    // On a CPU rasterizer W and Wᵀ read and write the vectors in place (host_products.h).
    const bool mapped = solverKernelsOnHost(device);
    for (auto [vector, name] : {std::pair{&obs, "obs"}, {&sqrtW, "sqrt-weights"}, {&rImg, "r-img"}, {&qImg, "q-img"},
                                {&tmpImg, "tmp-img"}, {&dImg, "d-img"}, {&rPrev, "r-prev"}})
        *vector = GpuVector(P, name, mapped);
    for (auto [vector, name] : {std::pair{&a, "a"}, {&aPrev, "a-prev"}, {&s, "s"}, {&p, "p"}, {&hull, "hull"}, {&tmpU, "tmp-u"},
                                {&precond, "precond"}, {&z, "z"}, {&movable, "movable"}})
        *vector = GpuVector(E, name, mapped);
    if (usesLaplacian())
        for (auto [vector, name] : {std::pair{&rLap, "r-lap"}, {&qLap, "q-lap"}, {&dLap, "d-lap"}}) *vector = GpuVector(E, name, mapped);
    if (usesIdentity()) rId = GpuVector(E, "r-id", mapped);
}

void Solver::State::buildObservations() {
    // The fixed part of each pixel (everything but the unknown's term, TVCG Eq. 5 and after),
    // from the renders the reach analysis takes too (reach.h: two per view, not six).
    const Unknown u = opt.unknown;
    if (cache) volumeKey = volumeKeyOf(volume, u);
    viewRenders = cachedRenderBounds(device, volume, volumeKey, lighting, views, opt, cache);
    auto fixedPart = [&](const ViewRenders& r) -> const Image& {
        switch (u) {
            case Unknown::Emission: return r.noEmission;
            case Unknown::Albedo: return r.albedo0;
            case Unknown::EmissionAlbedo: return r.neither;
            default: return r.background;  // extinction: what lies behind, L_bg per pixel
        }
    };
    const size_t P = W->pixelCount();
    std::vector<float> o(P * 4, 0.0f), w(P * 4, 0.0f);
    viewWeightSum.assign(views.size(), Vec3d(0.0));
    const Vec3d Lm = opt.mediumRadiance.value_or(Vec3d(0.0));
    size_t pixel = 0;
    for (size_t vi = 0; vi < views.size(); ++vi) {
        const SolveView& v = views[vi];
        const Image& F = fixedPart(*viewRenders[vi]);
        for (size_t i = 0; i < v.target.pixelCount(); ++i, ++pixel) {
            const float* t = &v.target.rgba[4 * i];
            const double weight = std::max(0.0f, t[3]) * (v.weights ? std::max(0.0f, v.weights->rgba[4 * i]) : 1.0f);
            bool constrained = false;
            for (int c = 0; c < 3; ++c) {
                const Observation ob = u == Unknown::Extinction ? observeTransmittance(t[c], F.rgba[4 * i + size_t(c)], Lm[c], weight, report)
                                                                : Observation{double(t[c]) - F.rgba[4 * i + size_t(c)], weight};
                o[4 * pixel + size_t(c)] = float(ob.value);
                w[4 * pixel + size_t(c)] = float(ob.weight);
                weightSum[c] += ob.weight;
                viewWeightSum[vi][c] += ob.weight;
                constrained |= ob.weight > 0;
            }
            report.constraintPixels += constrained ? 1 : 0;
        }
    }
    rawWeightHost = w;
    for (size_t i = 0; i < P; ++i)
        for (int c = 0; c < 3; ++c) {
            double sum = weightSum[c];
            w[4 * i + size_t(c)] = sum > 0 ? float(std::sqrt(w[4 * i + size_t(c)] / sum)) : 0.0f;
        }
    obs.upload(o);
    sqrtW.upload(w);
    sqrtWHost = std::move(w);
    obsHost = std::move(o);
}

void Solver::State::initialUnknowns() {
    // Warm start from the volume's current values, resampled onto the unknown grid.
    const Int3 n = volume.dims();
    std::vector<float> init(elements * 4, 0.0f);
    auto put = [&](const std::vector<float>& grid, size_t block) {
        if (volume.isSparse()) return sparseUnknownsFrom(grid, init, block);
        auto r = resample(GridView{grid, n}, udims, opt.basis, 4);
        std::copy(r.begin(), r.end(), init.begin() + std::ptrdiff_t(4 * block * cells));
    };
    switch (opt.unknown) {
        case Unknown::Emission:
            if (volume.hasEmission()) put(volume.emission(), 0);
            break;
        case Unknown::Albedo: put(Volume(volume).ensureAlbedo(), 0); break;
        case Unknown::EmissionAlbedo:
            if (volume.hasEmission()) put(volume.emission(), 0);
            put(Volume(volume).ensureAlbedo(), 1);
            break;
        case Unknown::Extinction: put(volume.extinction(), 0); break;
    }
    // Bounds (Sec. 5.1: a physically plausible, non-negative solution).
    bounds.blockSize = cells;
    if (opt.enforceBounds) {
        bounds.lower[0] = bounds.lower[1] = 0.0f;
        bounds.upper[0] = opt.unknown == Unknown::Albedo ? 1.0f : kUnbounded;
        bounds.upper[1] = 1.0f;  // the albedo block of a joint solve
    }
    for (size_t e = 0; e < elements; ++e) {
        size_t b = e / cells;
        for (int c = 0; c < 3; ++c) init[4 * e + size_t(c)] = std::clamp(init[4 * e + size_t(c)], bounds.lower[b], bounds.upper[b]);
    }
    a.upload(init);
    startsAtZero = std::all_of(init.begin(), init.end(), [](float x) { return x == 0.0f; });
}

void Solver::State::buildRegularizers() {
    // Regularizer scales per block, averaged over the block's hull unknowns.
    std::vector<Unknown> kinds = {opt.unknown};
    if (opt.unknown == Unknown::EmissionAlbedo) kinds = {Unknown::Emission, Unknown::Albedo};
    const double lp = opt.prior.values ? opt.prior.weight : 0.0;
    const std::vector<float> p = lp > 0 ? priorOnUnknowns() : std::vector<float>{};  // every block's, once
    for (size_t b = 0; b < kinds.size(); ++b) {
        size_t inHull = 0;
        for (size_t e = b * cells; e < (b + 1) * cells; ++e) inHull += hullHost[4 * e] > 0 ? 1 : 0;
        const double Mh = std::max<double>(1.0, double(inHull));
        const Regularization& reg = opt.regularizationFor(kinds[b]);
        const double lambda = reg.l2 + reg.towardOne + lp;
        BlockRegularizer br;
        br.range = {b * cells, cells};
        br.cLap = std::sqrt(reg.laplacian / Mh);
        br.cId = std::sqrt(lambda / Mh);
        br.target = lambda > 0 ? reg.towardOne / lambda : 0;
        if (lp > 0) {
            // λ0‖a‖² + λ1‖a − 1‖² + λp‖a − p‖² = λ‖a − t‖² + (λ1 + λp p² − λ t²), t = (λ1 + λp p)/λ.
            br.targets.assign(4 * cells, 0.0f);
            for (size_t e = 0; e < cells; ++e)
                for (int c = 0; c < 3; ++c) {
                    const double pe = p[3 * (b * cells + e) + size_t(c)], t = (reg.towardOne + lp * pe) / lambda;
                    br.targets[4 * e + size_t(c)] = float(t);
                    if (hullHost[4 * (b * cells + e)] > 0) constant[c] += (reg.towardOne + lp * pe * pe - lambda * t * t) / Mh;
                }
        } else {
            constant += Vec3d(lambda > 0 ? reg.l2 * reg.towardOne / lambda : 0);
        }
        blocks.push_back(br);
    }
}

void Solver::State::buildPreconditioner() {
    // Right (column) scaling, a change of variables a = D x that CGLS runs on A D: D² = 1 / (Aᵀ A 1)
    // per unknown and channel, the column scaling of SIRT. A's image rows are non-negative for
    // every unknown (opacity, opacity · in-scattering, Δt), so Aᵀ A 1 ≥ diag(AᵀA) > 0 wherever a
    // ray sees the unknown, and it costs one W and one Wᵀ. Unknowns that see a wide range of rays
    // (a cloud's rim against its core) then move at comparable rates: fewer iterations.
    // The regularizers' rows add their diagonal: c_id², and c_lap² · 42 (the 7-point Laplacian's
    // (LᵀL)_jj inside the hull).
    if (!opt.precondition) {
        precond.fill(1.0f);
        return;
    }
    ops.copy(hull, tmpU);  // 1 on the hull (rgb), 0 elsewhere
    W->forward(tmpU, tmpImg);
    ops.multiply(sqrtW, tmpImg);
    ops.multiply(sqrtW, tmpImg);
    W->adjoint(tmpImg, precond);
    std::vector<float> d = precond.download();
    std::vector<double> extra(elements, 0.0);
    for (const auto& b : blocks)
        for (size_t e = b.range.first; e < b.range.first + b.range.count; ++e) extra[e] = b.cId * b.cId + 42.0 * b.cLap * b.cLap;
    for (size_t e = 0; e < elements; ++e)
        for (int c = 0; c < 4; ++c) {
            const double v = c < 3 ? double(d[4 * e + c]) + extra[e] : 0.0;
            d[4 * e + c] = v > 0 && std::isfinite(v) ? float(1.0 / v) : 1.0f;  // unseen: unscaled (its gradient is 0)
        }
    precond.upload(d);
}

namespace {

/// Half the pixels along each axis: each target (weight, plate) pixel the mean of a 2×2 block, the
/// camera the same with half the size, so that its pixel centres are the blocks' centres.
Image halfImage(const Image& full, int w, int h) {
    Image out(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 4; ++c)
                out.pixel(x, y)[c] = 0.25f * (full.pixel(2 * x, 2 * y)[c] + full.pixel(2 * x + 1, 2 * y)[c] +
                                              full.pixel(2 * x, 2 * y + 1)[c] + full.pixel(2 * x + 1, 2 * y + 1)[c]);
    return out;
}

SolveView halfView(const SolveView& v) {
    SolveView h = v;
    h.camera.width = v.camera.width / 2, h.camera.height = v.camera.height / 2;
    h.target = halfImage(v.target, h.camera.width, h.camera.height);
    if (v.weights) h.weights = halfImage(*v.weights, h.camera.width, h.camera.height);
    if (v.background) h.background = std::make_shared<const Image>(halfImage(*v.background, h.camera.width, h.camera.height));
    return h;
}

}  // namespace

void Solver::State::warmStartFromCoarse(const std::atomic<bool>* cancel) {
    // The coarse problem costs about a sixteenth of the fine one per iteration (an eighth of the
    // unknowns, a quarter of the pixels, half the samples) and removes the error's smooth part,
    // which CGLS reduces slowest; the fine iterations are left with the detail.
    if (udims.x < 8 || udims.y < 8 || udims.z < 8) return;  // nothing to coarsen
    if (volume.isSparse()) return;  // its unknowns are its voxels: no coarser grid of them
    const auto t0 = Clock::now();
    std::vector<SolveView> coarseViews;
    for (const SolveView& v : views)
        if (v.camera.width >= 8 && v.camera.height >= 8) coarseViews.push_back(halfView(v));
    if (coarseViews.empty()) return;
    SolveOptions c = opt;
    c.resolution = Int3{udims.x / 2, udims.y / 2, udims.z / 2};
    c.stepVoxels = std::min(8.0, 2 * opt.stepVoxels);
    c.maxIterations = opt.coarseIterations;
    c.coarseIterations = 0;
    c.analyzeReach = false;
    c.views.clear();  // `views` holds the chosen ones already
    SolveResult r;
    try {
        r = Solver(device, volume, lighting, std::move(coarseViews), c).run({}, cancel);
    } catch (const InvalidArgument& e) {  // e.g. a view too small once halved: solve from cold
        spdlog::warn("solve: no coarse start ({}); starting from the volume as it is", e.what());
        return;
    }
    if (r.report.iterations == 0) return;
    volume = std::move(r.volume);
    initialUnknowns();  // the coarse result, resampled onto the fine grid
    report.coarseIterations = r.report.iterations;
    report.coarseMs = msSince(t0);
    spdlog::info("solve: coarse start, {} iterations at {}x{}x{} in {:.0f} ms (objective {:.3g} of its start)", r.report.iterations,
                 c.resolution->x, c.resolution->y, c.resolution->z, report.coarseMs,
                 r.report.finalObjective / std::max(r.report.initialObjective, 1e-300));
}

Volume Solver::State::result() {
    std::vector<float> av = a.download();
    Volume out = volume;
    const Int3 n = volume.dims();
    auto take = [&](size_t block) {
        return volume.isSparse() ? sparseGridFrom(av, block) : resample(GridView{av, udims, 4, 4 * block * cells}, n, opt.basis, 3);
    };
    switch (opt.unknown) {
        case Unknown::Emission: out.emission() = take(0); break;
        case Unknown::Albedo: out.albedo() = take(0); break;
        case Unknown::EmissionAlbedo:
            out.emission() = take(0);
            out.albedo() = take(1);
            break;
        case Unknown::Extinction: out.extinction() = take(0); break;
    }
    // Resampling can step past a bound by rounding only; keep the volume valid.
    if (opt.enforceBounds || opt.unknown == Unknown::Extinction) {
        for (float& x : out.extinction()) x = std::max(0.0f, x);
        for (float& x : out.emission()) x = std::max(0.0f, x);
        for (float& x : out.albedo()) x = std::clamp(x, 0.0f, 1.0f);
    }
    return out;
}

}  // namespace volstyle::core

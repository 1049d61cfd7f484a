#include "core/solve/solver.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <set>

#include "core/errors.h"
#include "core/render/gpu_volume.h"
#include "core/solve/gpu_vector.h"
#include "core/solve/projector.h"

namespace volstyle::core {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }


/// Trilinear (or nearest) lookup of an RGB grid with `stride` floats per voxel at index point q.
Vec3d sampleGrid(const std::vector<float>& g, Int3 n, const Vec3d& q, BasisType basis, int stride) {
    auto at = [&](int x, int y, int z) {
        size_t i = size_t(stride) * ((size_t(z) * n.y + size_t(y)) * n.x + size_t(x));
        return Vec3d(g[i], g[i + 1], g[i + 2]);
    };
    if (basis == BasisType::Box) {
        int c[3];
        for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor(q[a] + 0.5)), 0, n[a] - 1);
        return at(c[0], c[1], c[2]);
    }
    int i0[3], i1[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
        double qa = std::clamp(q[a], 0.0, double(n[a] - 1));
        i0[a] = std::min(int(std::floor(qa)), n[a] - 1);
        i1[a] = std::min(i0[a] + 1, n[a] - 1);
        f[a] = qa - i0[a];
    }
    Vec3d r(0.0);
    for (int c = 0; c < 8; ++c) {
        double w = ((c & 1) ? f[0] : 1 - f[0]) * ((c & 2) ? f[1] : 1 - f[1]) * ((c & 4) ? f[2] : 1 - f[2]);
        if (w != 0) r += at((c & 1) ? i1[0] : i0[0], (c & 2) ? i1[1] : i0[1], (c & 4) ? i1[2] : i0[2]) * w;
    }
    return r;
}

/// Resamples an RGB grid (3 floats per voxel) of dims `from` onto dims `to` (same box).
std::vector<float> resample(const std::vector<float>& g, Int3 from, Int3 to, BasisType basis, int strideIn, int strideOut,
                            size_t offsetIn = 0) {
    std::vector<float> out(size_t(to.volume()) * size_t(strideOut), 0.0f);
    const Vec3d scale(double(from.x) / to.x, double(from.y) / to.y, double(from.z) / to.z);
    std::vector<float> src(g.begin() + std::ptrdiff_t(offsetIn), g.end());
    for (int k = 0; k < to.z; ++k)
        for (int j = 0; j < to.y; ++j)
            for (int i = 0; i < to.x; ++i) {
                Vec3d q = (Vec3d(i, j, k) + Vec3d(0.5)) * scale - Vec3d(0.5);
                Vec3d v = from == to ? sampleGrid(src, from, Vec3d(i, j, k), BasisType::Box, strideIn)
                                     : sampleGrid(src, from, q, basis, strideIn);
                size_t o = size_t(strideOut) * ((size_t(k) * to.y + size_t(j)) * to.x + size_t(i));
                out[o] = float(v.x), out[o + 1] = float(v.y), out[o + 2] = float(v.z);
            }
    return out;
}

}  // namespace

struct Solver::State {
    Renderer& renderer;
    Volume volume;
    Lighting lighting;
    std::vector<SolveView> views;
    SolveOptions opt;

    Int3 udims;
    size_t cells = 0, elements = 0;
    std::unique_ptr<GpuVolume> gpu;
    std::unique_ptr<Projector> W;
    VectorOps ops;
    GpuVector a, aPrev, s, p, hull, obs, sqrtW, rImg, qImg, tmpImg, dImg, rLap, qLap, dLap, tmpU, rId;
    Bounds bounds;
    /// Regularizer rows of one block of unknowns (emission, albedo or extinction): √(λ_lap/M) L,
    /// √((λ0+λ1)/M) (a − t) with t = λ1/(λ0+λ1), M the block's hull unknowns.
    struct BlockRegularizer {
        Range range;
        double cLap = 0, cId = 0, target = 0;
    };
    std::vector<BlockRegularizer> blocks;
    Vec3d constant{0, 0, 0};  // λ0‖a‖² + λ1‖a−1‖² = λ‖a−t‖² + λ0λ1/λ per element
    Vec3d weightSum{0, 0, 0};
    std::vector<Vec3d> viewWeightSum;
    std::vector<float> hullHost;
    SolveReport report;

    State(Renderer& r, const Volume& v, const Lighting& l, std::vector<SolveView> vs, SolveOptions o)
        : renderer(r), volume(v), lighting(l), views(std::move(vs)), opt(std::move(o)), ops(r) {}

    void validateInputs();
    void buildObservations();
    void buildHull();
    void initialUnknowns();
    void applyA(const GpuVector& x, GpuVector& img, GpuVector& lap);  // [img; lap] = A x (identity rows implicit)
    /// Moves a by step·x with residuals [rImg; rLap; rId] updated by the matching A x = [img; lap].
    void move(const Vec3d& step, const GpuVector& x, const GpuVector& img, const GpuVector& lap);
    void applyAt();                                  // s from rImg, rLap, rId
    void restart(Vec3d& gamma);
    Vec3d objective();
    std::vector<double> rmsPerView();
    Volume result();
};

Solver::Solver(Renderer& renderer, const Volume& volume, const Lighting& lighting, std::vector<SolveView> views,
               SolveOptions options)
    : m_state(std::make_unique<State>(renderer, volume, lighting, std::move(views), std::move(options))) {
    State& st = *m_state;
    st.validateInputs();
    st.udims = st.opt.resolution.value_or(st.volume.dims());
    st.cells = size_t(st.udims.volume());
    st.elements = st.cells * (st.opt.unknown == Unknown::EmissionAlbedo ? 2 : 1);
    st.gpu = std::make_unique<GpuVolume>(st.volume);
    st.W = std::make_unique<Projector>(renderer, *st.gpu, st.lighting, st.opt.unknown, st.opt.basis, st.udims,
                                       st.opt.stepVoxels, st.opt.exactTraversal);
    for (const auto& v : st.views) st.W->addView(v.camera);
    const size_t P = st.W->pixelCount(), E = st.elements;
    st.obs = GpuVector(P, "obs"), st.sqrtW = GpuVector(P, "sqrt-weights"), st.rImg = GpuVector(P, "r-img");
    st.qImg = GpuVector(P, "q-img"), st.tmpImg = GpuVector(P, "tmp-img"), st.dImg = GpuVector(P, "d-img");
    st.dLap = GpuVector(E, "d-lap");
    st.a = GpuVector(E, "a"), st.aPrev = GpuVector(E, "a-prev"), st.s = GpuVector(E, "s"), st.p = GpuVector(E, "p");
    st.hull = GpuVector(E, "hull"), st.rLap = GpuVector(E, "r-lap"), st.qLap = GpuVector(E, "q-lap");
    st.tmpU = GpuVector(E, "tmp-u"), st.rId = GpuVector(E, "r-id");
    st.buildObservations();
    st.buildHull();
    st.initialUnknowns();
}

Solver::~Solver() = default;

void Solver::State::validateInputs() {
    opt.validate();
    volume.validate();
    lighting.validate();
    // Keep the requested views (all with a target by default).
    std::vector<SolveView> chosen;
    std::set<std::string> wanted(opt.views.begin(), opt.views.end());
    for (auto& v : views) {
        if (!wanted.empty() && !wanted.count(v.name)) continue;
        wanted.erase(v.name);
        if (v.target.empty()) {
            if (!opt.views.empty()) throw InvalidArgument("view '" + v.name + "' has no target");
            continue;
        }
        chosen.push_back(std::move(v));
    }
    if (!wanted.empty()) throw InvalidArgument("solve options: views: no view named '" + *wanted.begin() + "'");
    if (chosen.empty()) throw InvalidArgument("solve: no view has a target image; upload a painted target first");
    for (const auto& v : chosen) {
        const std::string name = "view '" + v.name + "'";
        try {
            v.camera.validate();
        } catch (const InvalidArgument& e) {
            throw InvalidArgument(name + ": " + e.what());
        }
        if (v.target.width != v.camera.width || v.target.height != v.camera.height)
            throw InvalidArgument(name + ": the target is " + std::to_string(v.target.width) + "x" +
                                  std::to_string(v.target.height) + " but the camera renders " +
                                  std::to_string(v.camera.width) + "x" + std::to_string(v.camera.height));
        if (size_t bad = v.target.countNonFinite())
            throw InvalidArgument(name + ": the target has " + std::to_string(bad) + " non-finite (NaN/Inf) values");
        if (v.weights) {
            if (v.weights->width != v.target.width || v.weights->height != v.target.height)
                throw InvalidArgument(name + ": the weight image size differs from the target's");
            if (size_t bad = v.weights->countNonFinite())
                throw InvalidArgument(name + ": the weight image has " + std::to_string(bad) + " non-finite values");
        }
    }
    views = std::move(chosen);
}

void Solver::State::buildObservations() {
    // The fixed part of each pixel (everything but the unknown's term, TVCG Eq. 5 and after):
    // rendered from a copy of the volume with the unknown's contribution removed.
    Volume fixed = volume;
    Lighting fixedLighting = lighting;
    const Unknown u = opt.unknown;
    if (u == Unknown::Emission || u == Unknown::EmissionAlbedo) fixed.emission().clear();
    if (u == Unknown::Albedo || u == Unknown::EmissionAlbedo) fixed.ensureAlbedo(0.0f).assign(fixed.voxelCount() * 3, 0.0f);
    if (u == Unknown::Extinction) {
        fixed.extinction().assign(fixed.voxelCount() * 3, 0.0f);  // what lies behind: L_bg per pixel
        fixedLighting.lights.clear();
    }
    GpuVolume fixedGpu(fixed);
    RenderSettings settings;
    settings.stepVoxels = opt.stepVoxels;
    settings.exactTraversal = opt.exactTraversal;

    const size_t P = W->pixelCount();
    std::vector<float> o(P * 4, 0.0f), w(P * 4, 0.0f);
    viewWeightSum.assign(views.size(), Vec3d(0.0));
    const Vec3d Lm = opt.mediumRadiance.value_or(Vec3d(0.0));
    size_t pixel = 0;
    for (size_t vi = 0; vi < views.size(); ++vi) {
        const SolveView& v = views[vi];
        Image F = renderer.render(fixedGpu, v.camera, fixedLighting, settings);
        for (size_t i = 0; i < v.target.pixelCount(); ++i, ++pixel) {
            const float* t = &v.target.rgba[4 * i];
            double weight = std::max(0.0f, t[3]) * (v.weights ? std::max(0.0f, v.weights->rgba[4 * i]) : 1.0f);
            bool constrained = false;
            for (int c = 0; c < 3; ++c) {
                double wc = weight, oc = 0;
                if (u == Unknown::Extinction) {
                    // Sec. 4.2.4: o = −ln((L − L_m) / (L_bg − L_m)).
                    double denom = double(F.rgba[4 * i + size_t(c)]) - Lm[c];
                    double ratio = std::abs(denom) < 1e-6 ? -1 : (double(t[c]) - Lm[c]) / denom;
                    if (wc > 0 && !(ratio > 0)) {
                        wc = 0;
                        report.ignoredPixels++;
                    } else if (wc > 0 && ratio > 1) {
                        ratio = 1;
                        report.clampedPixels++;
                    }
                    oc = wc > 0 ? -std::log(ratio) : 0;
                } else {
                    oc = double(t[c]) - F.rgba[4 * i + size_t(c)];
                }
                o[4 * pixel + size_t(c)] = float(oc);
                w[4 * pixel + size_t(c)] = float(wc);
                weightSum[c] += wc;
                viewWeightSum[vi][c] += wc;
                constrained |= wc > 0;
            }
            report.constraintPixels += constrained ? 1 : 0;
        }
    }
    for (size_t i = 0; i < P; ++i)
        for (int c = 0; c < 3; ++c) {
            double sum = weightSum[c];
            w[4 * i + size_t(c)] = sum > 0 ? float(std::sqrt(w[4 * i + size_t(c)] / sum)) : 0.0f;
        }
    obs.upload(o);
    sqrtW.upload(w);
}

void Solver::State::buildHull() {
    const Int3 n = volume.dims();
    hullHost.assign(elements * 4, 0.0f);
    const Vec3d scale(double(udims.x) / n.x, double(udims.y) / n.y, double(udims.z) / n.z);
    auto mark = [&](int i, int j, int k) {
        for (size_t b = 0; b < elements / cells; ++b) {
            size_t e = b * cells + (size_t(k) * udims.y + size_t(j)) * udims.x + size_t(i);
            hullHost[4 * e] = hullHost[4 * e + 1] = hullHost[4 * e + 2] = 1.0f;
        }
    };
    if (!opt.useHull) {
        for (int k = 0; k < udims.z; ++k)
            for (int j = 0; j < udims.y; ++j)
                for (int i = 0; i < udims.x; ++i) mark(i, j, k);
    } else if (opt.unknown != Unknown::Extinction) {
        // Unknowns whose basis support overlaps non-zero extinction (TVCG Sec. 5.2, visual hulls):
        // the rest have no influence on any pixel.
        for (int k = 0; k < n.z; ++k)
            for (int j = 0; j < n.y; ++j)
                for (int i = 0; i < n.x; ++i) {
                    if (maxComponent(volume.extinctionAt(i, j, k)) <= 0) continue;
                    int lo[3], hi[3];
                    for (int a = 0; a < 3; ++a) {
                        int v = a == 0 ? i : (a == 1 ? j : k);
                        double qlo = (v - 1 + 0.5) * scale[a] - 0.5, qhi = (v + 1 + 0.5) * scale[a] - 0.5;
                        lo[a] = std::clamp(int(std::floor(qlo)), 0, udims[a] - 1);
                        hi[a] = std::clamp(int(std::ceil(qhi)), 0, udims[a] - 1);
                    }
                    for (int z = lo[2]; z <= hi[2]; ++z)
                        for (int y = lo[1]; y <= hi[1]; ++y)
                            for (int x = lo[0]; x <= hi[0]; ++x) mark(x, y, z);
                }
    } else {
        // Extinction: carve with the targets' masks. An unknown whose centre a view sees through a
        // constrained pixel that shows only background (o = 0) is outside the hull.
        std::vector<float> o = obs.download(), w = sqrtW.download();
        const Mat4& worldFromIndex = volume.worldFromIndex();
        for (int k = 0; k < udims.z; ++k)
            for (int j = 0; j < udims.y; ++j)
                for (int i = 0; i < udims.x; ++i) {
                    Vec3d pIndex = (Vec3d(i, j, k) + Vec3d(0.5)) / scale - Vec3d(0.5);
                    Vec3d pw = worldFromIndex.applyPoint(pIndex);
                    bool inside = true;
                    size_t offset = 0;
                    for (const auto& v : views) {
                        const Camera& c = v.camera;
                        Camera::Frame f = c.frame();
                        Vec3d rel = pw - c.eye;
                        double z = dot(rel, f.forward);
                        double tanHalf = std::tan(c.fovYDeg * std::numbers::pi / 360.0);
                        if (z > 0) {
                            double x = dot(rel, f.right) / (z * tanHalf * c.width / c.height);
                            double y = dot(rel, f.up) / (z * tanHalf);
                            int px = int(std::floor((x + 1) / 2 * c.width)), py = int(std::floor((1 - y) / 2 * c.height));
                            if (px >= 0 && py >= 0 && px < c.width && py < c.height) {
                                size_t idx = 4 * (offset + size_t(py) * c.width + size_t(px));
                                bool constrained = w[idx] > 0 || w[idx + 1] > 0 || w[idx + 2] > 0;
                                bool empty = o[idx] <= 1e-6f && o[idx + 1] <= 1e-6f && o[idx + 2] <= 1e-6f;
                                if (constrained && empty) inside = false;
                            }
                        }
                        offset += size_t(c.width) * c.height;
                    }
                    if (inside) mark(i, j, k);
                }
    }
    hull.upload(hullHost);
    size_t count = 0;
    for (size_t e = 0; e < elements; ++e) count += hullHost[4 * e] > 0 ? 1 : 0;
    report.unknownCount = elements;
    report.hullCount = count;
}

void Solver::State::initialUnknowns() {
    // Warm start from the volume's current values, resampled onto the unknown grid.
    const Int3 n = volume.dims();
    std::vector<float> init(elements * 4, 0.0f);
    auto put = [&](const std::vector<float>& grid, size_t block) {
        auto r = resample(grid, n, udims, opt.basis, 3, 4);
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
    const float inf = 3e38f;
    bounds.blockSize = cells;
    if (opt.enforceBounds) {
        bounds.lower[0] = bounds.lower[1] = 0.0f;
        bounds.upper[0] = opt.unknown == Unknown::Albedo ? 1.0f : inf;
        bounds.upper[1] = 1.0f;  // the albedo block of a joint solve
    }
    for (size_t e = 0; e < elements; ++e) {
        size_t b = e / cells;
        for (int c = 0; c < 3; ++c) init[4 * e + size_t(c)] = std::clamp(init[4 * e + size_t(c)], bounds.lower[b], bounds.upper[b]);
    }
    a.upload(init);

    // Regularizer scales per block, averaged over the block's hull unknowns.
    std::vector<Unknown> kinds = {opt.unknown};
    if (opt.unknown == Unknown::EmissionAlbedo) kinds = {Unknown::Emission, Unknown::Albedo};
    for (size_t b = 0; b < kinds.size(); ++b) {
        size_t inHull = 0;
        for (size_t e = b * cells; e < (b + 1) * cells; ++e) inHull += hullHost[4 * e] > 0 ? 1 : 0;
        const double Mh = std::max<double>(1.0, double(inHull));
        const Regularization& reg = opt.regularizationFor(kinds[b]);
        const double lambda = reg.l2 + reg.towardOne;
        BlockRegularizer br;
        br.range = {b * cells, cells};
        br.cLap = std::sqrt(reg.laplacian / Mh);
        br.cId = std::sqrt(lambda / Mh);
        br.target = lambda > 0 ? reg.towardOne / lambda : 0;
        blocks.push_back(br);
        constant += Vec3d(lambda > 0 ? reg.l2 * reg.towardOne / lambda : 0);
    }
}

void Solver::State::applyA(const GpuVector& x, GpuVector& img, GpuVector& lap) {
    W->forward(x, img);
    ops.multiply(sqrtW, img);
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
    ops.multiply(hull, s);
    if (opt.enforceBounds) ops.freeSet(a, s, bounds);
}

void Solver::State::restart(Vec3d& gamma) {
    // r = b − A a, from scratch (also clears the drift of the recurrences).
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
            if (i % 4 != 3 && hullHost[i - i % 4] > 0) r[i] = float(b.cId * (b.target - av[i]));
    }
    if (!r.empty()) rId.upload(r);
    applyAt();
    ops.copy(s, p);
    gamma = ops.dot(s, s);
}

Vec3d Solver::State::objective() {
    Vec3d f = ops.dot(rImg, rImg) + constant;
    bool lap = false, id = false;
    for (const auto& b : blocks) lap |= b.cLap > 0, id |= b.cId > 0;
    if (lap) f += ops.dot(rLap, rLap);
    if (id) f += ops.dot(rId, rId);
    return f;
}

std::vector<double> Solver::State::rmsPerView() {
    std::vector<double> out;
    for (size_t v = 0; v < views.size(); ++v) {
        Vec3d r2 = ops.dot(rImg, rImg, W->viewRange(v));
        double sum = 0;
        int channels = 0;
        for (int c = 0; c < 3; ++c) {
            if (viewWeightSum[v][c] <= 0) continue;
            sum += std::sqrt(std::max(0.0, r2[c] * weightSum[c] / viewWeightSum[v][c]));
            ++channels;
        }
        out.push_back(channels ? sum / channels : 0.0);
    }
    return out;
}

Volume Solver::State::result() {
    std::vector<float> av = a.download();
    Volume out = volume;
    const Int3 n = volume.dims();
    auto take = [&](size_t block) { return resample(av, udims, n, opt.basis, 4, 3, 4 * block * cells); };
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

Volume Solver::currentVolume() { return m_state->result(); }

SolveResult Solver::run(const ProgressCallback& progress, const std::atomic<bool>* cancel) {
    State& st = *m_state;
    SolveReport& rep = st.report;
    const auto t0 = Clock::now();
    if (rep.constraintPixels == 0 || rep.hullCount == 0) {
        rep.stopReason = rep.constraintPixels == 0 ? "no_constraints" : "empty_hull";
        spdlog::warn("solve: nothing to solve ({})", rep.stopReason);
        return {st.volume, rep};
    }
    Vec3d gamma;  // ‖s‖², s = Aᵀr restricted to the free variables
    st.restart(gamma);
    Vec3d slope = gamma;  // p·s: the objective's descent rate along p (= γ in plain CGLS)
    double f = [&] { Vec3d v = st.objective(); return v.x + v.y + v.z; }();
    rep.initialObjective = f;
    rep.objectiveHistory.push_back(f);
    rep.initialRms = st.rmsPerView();
    rep.finalRms = rep.initialRms;
    int flat = 0;
    constexpr int kRestartEvery = 25;

    for (int it = 1; it <= st.opt.maxIterations; ++it) {
        if (cancel && cancel->load()) throw Cancelled("solve cancelled after " + std::to_string(it - 1) + " iterations");
        const auto tIt = Clock::now();
        const ProjectorStats before = st.W->stats();
        if (gamma.x <= 0 && gamma.y <= 0 && gamma.z <= 0) {
            rep.stopReason = "zero_gradient";
            break;
        }
        // Step along p: α = γ / ‖A p‖² (the exact line minimum).
        st.applyA(st.p, st.qImg, st.qLap);
        Vec3d delta = st.ops.dot(st.qImg, st.qImg);
        for (const auto& b : st.blocks) {
            if (b.cLap > 0) delta += st.ops.dot(st.qLap, st.qLap, b.range);
            if (b.cId > 0) delta += st.ops.dot(st.p, st.p, b.range) * (b.cId * b.cId);
        }
        Vec3d alpha, maxStep(1e300);
        bool hit[3] = {false, false, false};
        if (st.opt.enforceBounds) maxStep = st.ops.maxStep(st.a, st.p, st.bounds);
        for (int c = 0; c < 3; ++c) {
            alpha[c] = delta[c] > 0 && slope[c] > 0 ? slope[c] / delta[c] : 0.0;
            hit[c] = maxStep[c] < alpha[c];
        }
        st.ops.copy(st.a, st.aPrev);
        if (!(hit[0] || hit[1] || hit[2])) {
            st.move(alpha, st.p, st.qImg, st.qLap);
        } else if (st.opt.boundsMethod == BoundsMethod::CutAtBound) {
            Vec3d cut;
            for (int c = 0; c < 3; ++c) cut[c] = hit[c] ? maxStep[c] : alpha[c];
            st.move(cut, st.p, st.qImg, st.qLap);
            st.ops.clamp(st.a, st.bounds);  // rounding only
        } else {
            // The step leaves the box in some channel. Try the projected step a' = clamp(a + αp):
            // it moves many variables at once (in channels that stay inside it is the plain CG
            // step). Its residual needs A (a' − a), one more projection. Channels where a' lowers
            // the objective keep it; the others take the step cut at the first bound, which always
            // lowers it. Channels that met a bound restart from their gradient.
            const Vec3d fBefore = st.objective();
            st.ops.axpy(alpha, st.p, st.a);
            st.ops.clamp(st.a, st.bounds);
            st.ops.copy(st.a, st.tmpU);
            st.ops.axpy(Vec3d(-1.0), st.aPrev, st.tmpU);  // d = a' − a
            st.ops.copy(st.aPrev, st.a);
            st.applyA(st.tmpU, st.dImg, st.dLap);
            st.move(Vec3d(1.0), st.tmpU, st.dImg, st.dLap);
            const Vec3d fProjected = st.objective();
            Vec3d undo(0.0), cut(0.0);
            for (int c = 0; c < 3; ++c) {
                if (!hit[c] || fProjected[c] <= fBefore[c]) continue;
                undo[c] = -1.0;  // reject the projected step in this channel
                cut[c] = maxStep[c];
            }
            if (maxComponent(-undo) > 0) {
                st.move(undo, st.tmpU, st.dImg, st.dLap);
                st.move(cut, st.p, st.qImg, st.qLap);
            }
            st.ops.clamp(st.a, st.bounds);  // rounding only: every move above stays inside
        }

        Vec3d fv = st.objective();
        double fNew = fv.x + fv.y + fv.z;
        if (!std::isfinite(fNew)) {
            st.ops.copy(st.aPrev, st.a);  // keep the last finite iterate
            rep.stopReason = "numerical_breakdown";
            spdlog::warn("solve: objective became non-finite at iteration {}; keeping iteration {}", it, it - 1);
            break;
        }
        // New gradient and direction. Plain CGLS sets β = γ'/γ. When the free set changes the old
        // direction is no longer conjugate; keep β only while p stays a clear descent direction
        // (p·s ≥ 0.2 ‖s‖²), else restart that channel from its gradient. Steps use the exact line
        // minimum p·s / ‖A p‖², so every step lowers the objective.
        Vec3d gammaNew;
        if (it % kRestartEvery == 0) {
            st.restart(gammaNew);  // refreshes the recurrences' residuals from scratch
            slope = gammaNew;
        } else {
            st.applyAt();
            gammaNew = st.ops.dot(st.s, st.s);
            const Vec3d ps = st.ops.dot(st.p, st.s);
            Vec3d beta;
            for (int c = 0; c < 3; ++c) {
                beta[c] = gamma[c] > 0 ? gammaNew[c] / gamma[c] : 0.0;
                if (gammaNew[c] + beta[c] * ps[c] < 0.2 * gammaNew[c]) beta[c] = 0.0;
                slope[c] = gammaNew[c] + beta[c] * ps[c];
            }
            st.ops.xpby(st.s, beta, st.p);
        }
        gamma = gammaNew;

        rep.iterations = it;
        rep.objectiveHistory.push_back(fNew);
        rep.finalRms = st.rmsPerView();
        const ProjectorStats& after = st.W->stats();
        SolveProgress pr;
        pr.iteration = it;
        pr.objective = fNew;
        pr.rmsPerView = rep.finalRms;
        pr.elapsedMs = msSince(t0);
        pr.forwardMs = after.forwardMs - before.forwardMs;
        pr.adjointMs = after.adjointMs - before.adjointMs;
        pr.vectorMs = std::max(0.0, msSince(tIt) - pr.forwardMs - pr.adjointMs);
        rep.forwardMs += pr.forwardMs, rep.adjointMs += pr.adjointMs, rep.vectorMs += pr.vectorMs;
        if (progress) progress(pr);

        // Stopping rules: relative decrease below tolerance (unless a bound cut the step short),
        // or no decrease at all three times in a row.
        const bool anyHit = hit[0] || hit[1] || hit[2];
        const double decrease = (f - fNew) / std::max(f, 1e-300);
        f = fNew;
        flat = decrease <= 1e-12 ? flat + 1 : 0;
        if (flat >= 3) {
            rep.stopReason = "stagnated";
            break;
        }
        if (!anyHit && decrease >= 0 && decrease < st.opt.tolerance) {
            rep.stopReason = "converged";
            break;
        }
        if (it == st.opt.maxIterations) rep.stopReason = "max_iterations";
    }
    if (rep.stopReason.empty()) rep.stopReason = "max_iterations";
    rep.finalObjective = rep.objectiveHistory.back();
    rep.totalMs = msSince(t0);
    return {st.result(), rep};
}

}  // namespace volstyle::core

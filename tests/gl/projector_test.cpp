// The solver's operator W and its adjoint (TVCG Listing 1): the adjoint identity
// ⟨W a, r⟩ = ⟨a, Wᵀ r⟩ for every unknown × basis (≤ 1e-4 relative on the GL path, float32
// accumulation; ≤ 1e-12 in the float64 oracle), and the GL operator against the oracle.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "core/cpu_ref/reference_projector.h"
#include "core/solve/projector.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

struct Problem {
    Volume volume;
    Lighting lighting;
    std::vector<Camera> cameras;
};

/// `dense`: extinction up to 40 per world unit (3 optical depths a segment of 0.5 voxel), so the
/// march cuts dense segments into pieces (march.glsl splitDense, issue #34) on both sides.
Problem makeProblem(uint32_t seed, bool dense = false) {
    // Odd sizes: a ray crossing the box face to face in n equal segments then never has a
    // midpoint on a voxel face, where the box basis is discontinuous and float and double would
    // pick different voxels.
    Int3 dims{11, 9, 13};
    Problem p{Volume(dims, unitBoxWorldFromIndex(dims)), Lighting{}, {}};
    std::mt19937 rng(seed);
    auto u = [&] { return float(rng() % 100000) / 100000.0f; };
    for (size_t i = 0; i < p.volume.voxelCount(); ++i) {
        bool hole = u() < 0.25f;
        for (int c = 0; c < 3; ++c) p.volume.extinction()[3 * i + size_t(c)] = hole ? 0.0f : (dense ? 40.0f : 4.0f) * u();
    }
    p.lighting.lights = {{{0.3, 0.8, 0.2}, {3, 2.5, 2}}, {{-0.6, 0.2, 0.7}, {1, 1.5, 2}}};
    p.lighting.phase = {PhaseType::HenyeyGreenstein, 0.3};
    for (int v = 0; v < 2; ++v) {
        Camera c;
        // Off-centre on purpose: rays through the grid's centre meet voxel faces exactly.
        c.eye = {2.6 * std::sin(1.3 * v + 0.2) + 0.0137, 0.7 - 0.9 * v + 0.0071, 2.6 * std::cos(1.3 * v + 0.2)};
        c.target = {0.0123, -0.0091, 0.0057};
        c.width = 16, c.height = 12;
        c.fovYDeg = 50;
        p.cameras.push_back(c);
    }
    return p;
}

std::vector<double> randomVector(size_t elements, uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<double> v(elements * 4, 0.0);
    for (size_t i = 0; i < elements; ++i)
        for (int c = 0; c < 3; ++c) v[4 * i + size_t(c)] = double(rng() % 200001) / 100000.0 - 1.0;
    return v;
}

std::vector<float> toFloat(const std::vector<double>& v) { return {v.begin(), v.end()}; }

Vec3d dot(const std::vector<double>& a, const std::vector<float>& b) {
    Vec3d s(0.0);
    for (size_t i = 0; i < a.size(); i += 4)
        for (int c = 0; c < 3; ++c) s[c] += a[i + size_t(c)] * double(b[i + size_t(c)]);
    return s;
}
Vec3d dot(const std::vector<double>& a, const std::vector<double>& b) {
    Vec3d s(0.0);
    for (size_t i = 0; i < a.size(); i += 4)
        for (int c = 0; c < 3; ++c) s[c] += a[i + size_t(c)] * b[i + size_t(c)];
    return s;
}

struct Case {
    Unknown unknown;
    BasisType basis;
    bool coarse;
    bool dense = false;
};

/// How W and Wᵀ run: matrix-free with float atomics or the compare-and-swap loop, or from the
/// cached rows (sparse_rows.h; `budget` bytes, so a small one leaves some views matrix-free).
struct Path {
    bool floatAtomics = true;
    bool cached = false;
    size_t budget = size_t(1) << 30;
    int expectCachedViews = -1;  ///< -1: all views
    int columnsOnHost = -1;      ///< the rows' columns: 1 transposed on the host, 0 by the fill pass's atomics, -1 the device's default
    int productsOnHost = -1;     ///< W and Wᵀ from the rows: 1 on the host (host_products.h), 0 by sparse_project.comp, -1 the device's default
    int mergeViews = -1;         ///< the views' rows merged into one: 1, 0, or -1 the device's default (not on a CPU rasterizer)
};

void checkCase(const Case& k, const Path& path) {
    const bool floatAtomics = path.floatAtomics;
    Problem prob = makeProblem(7, k.dense);
    const Int3 udims = k.coarse ? Int3{5, 5, 7} : prob.volume.dims();
    GpuVolume gpu(prob.volume);
    Projector W(test::device(), gpu, prob.lighting, k.unknown, k.basis, udims, 0.5);
    if (!floatAtomics) W.setUseFloatAtomics(false);
    if (path.columnsOnHost >= 0) W.setColumnsOnHost(path.columnsOnHost == 1);
    // The host computes W and Wᵀ only with vectors it can map (as the solver's, on a CPU rasterizer).
    const bool mapped = path.productsOnHost < 0 ? test::device().capabilities().isSoftware : path.productsOnHost == 1;
    W.setProductsOnHost(mapped);
    if (path.mergeViews >= 0) W.setMergeViews(path.mergeViews == 1);
    if (path.productsOnHost == 1 && path.columnsOnHost < 0) W.setColumnsOnHost(true);  // host products need mapped rows (a GPU maps none)
    for (const auto& c : prob.cameras) W.addView(c);
    if (path.cached) {
        W.cacheRows(path.budget, weightChannels(prob.volume, prob.lighting, k.unknown));
        EXPECT_EQ(W.stats().cachedViews, path.expectCachedViews < 0 ? prob.cameras.size() : size_t(path.expectCachedViews));
        EXPECT_LE(W.stats().cacheBytes, path.budget);
    }
    cpu_ref::ReferenceProjector ref(prob.volume, prob.lighting, prob.cameras, {k.unknown, k.basis, udims, 0.5});
    ASSERT_EQ(ref.pixelCount(), W.pixelCount());
    ASSERT_EQ(ref.elementCount(), W.elementCount());

    auto a = randomVector(W.elementCount(), 1), r = randomVector(W.pixelCount(), 2);
    GpuVector ga(W.elementCount(), "a", mapped), gr(W.pixelCount(), "r", mapped), gWa(W.pixelCount(), "Wa", mapped),
        gWtr(W.elementCount(), "Wtr", mapped);
    ga.upload(toFloat(a));
    gr.upload(toFloat(r));
    W.forward(ga, gWa);
    W.adjoint(gr, gWtr);
    auto Wa = gWa.download(), Wtr = gWtr.download();

    // GL adjoint identity, per channel.
    Vec3d lhs = dot(r, Wa), rhs = dot(a, Wtr);
    for (int c = 0; c < 3; ++c) {
        double scale = std::max(std::abs(lhs[c]), 1e-3);
        EXPECT_LE(std::abs(lhs[c] - rhs[c]) / scale, 1e-4) << "channel " << c << ": " << lhs[c] << " vs " << rhs[c];
    }
    // Float64 oracle: adjoint identity to rounding, and the GL operator agrees with it.
    auto refWa = ref.forward(a), refWtr = ref.adjoint(r);
    Vec3d refL = dot(r, refWa), refR = dot(a, refWtr);
    for (int c = 0; c < 3; ++c) EXPECT_LE(std::abs(refL[c] - refR[c]), 1e-12 * std::max(1.0, std::abs(refL[c])));
    // Trilinear: every value within 1e-4 of the peak. Box: the basis is discontinuous, so a sample
    // within float rounding of a voxel face may land in the neighbour in one and not the other;
    // allow such flips in at most 1% of the values, the rest within 1e-4.
    auto compare = [&](const std::vector<double>& want, const std::vector<float>& got, const char* what) {
        double peak = 0, worst = 0;
        for (size_t i = 0; i < want.size(); ++i) peak = std::max(peak, std::abs(want[i]));
        size_t off = 0;
        for (size_t i = 0; i < want.size(); ++i) {
            double e = std::abs(want[i] - got[i]);
            if (e > 1e-4 * peak) ++off;
            else worst = std::max(worst, e);
        }
        EXPECT_GT(peak, 0.0) << what;
        if (k.basis == BasisType::Trilinear) EXPECT_EQ(off, 0u) << what;
        else EXPECT_LE(double(off), 0.01 * double(want.size())) << what;
        return worst / peak;
    };
    double errF = compare(refWa, Wa, "forward"), errA = compare(refWtr, Wtr, "adjoint");
    if (path.cached && W.merged()) {
        // Only the merged rows are kept (issue #40); each view is a range of them.
        const auto m = W.mergedRows();
        EXPECT_EQ(W.rowsOf(0), nullptr);
        EXPECT_EQ(W.stats().cacheBytes, sparseRowsBytes(m->rows, m->columns, m->entries, m->channels));
    }
    if (path.cached && W.allCached()) {
        // W_v and W_vᵀ (a range of the merged rows, or the view's own) against the oracle over the
        // view's pixels alone.
        for (size_t v = 0; v < W.viewCount(); ++v) {
            const Range px = W.viewRange(v);
            std::vector<double> rv(r.size(), 0.0);
            std::copy_n(r.begin() + std::ptrdiff_t(4 * px.first), 4 * px.count, rv.begin() + std::ptrdiff_t(4 * px.first));
            GpuVector viewWa(W.pixelCount(), "Wv a", mapped), viewWtr(W.elementCount(), "Wvt r", mapped);
            viewWa.fill(0.0f);
            W.forwardView(v, ga, viewWa);
            W.adjointView(v, gr, viewWtr);
            std::vector<double> refView(refWa.size(), 0.0);
            std::copy_n(refWa.begin() + std::ptrdiff_t(4 * px.first), 4 * px.count, refView.begin() + std::ptrdiff_t(4 * px.first));
            compare(refView, viewWa.download(), "one view's forward from its rows");
            compare(ref.adjoint(rv), viewWtr.download(), "one view's adjoint from its rows");
        }
    }
    std::cout << "[ measured ] unknown " << int(k.unknown) << " basis " << int(k.basis) << (k.coarse ? " coarse" : "") << (k.dense ? " dense" : "")
              << (path.cached ? " cached rows (" + std::to_string(W.stats().cachedViews) + " views" + (mapped ? ", products on the host)" : ")")
                              : floatAtomics ? " atomics" : " CAS")
              << ": identity " << std::abs(lhs.x - rhs.x) / std::abs(lhs.x)
              << ", forward vs float64 " << errF << ", adjoint vs float64 " << errA << "\n";
}

}  // namespace

class ProjectorAdjoint : public ::testing::TestWithParam<Case> {};

TEST_P(ProjectorAdjoint, IdentityAndOracle) {
    VOLSTYLE_REQUIRE_GL();
    checkCase(GetParam(), {test::glContext()->capabilities().hasFloatAtomics});
}

// The cached rows hold the same entries as the rays: the same oracle, the same tolerances.
TEST_P(ProjectorAdjoint, CachedRowsMatchTheOracle) {
    VOLSTYLE_REQUIRE_GL();
    checkCase(GetParam(), {true, true});
}

INSTANTIATE_TEST_SUITE_P(AllUnknownsAndBases, ProjectorAdjoint,
                         ::testing::Values(Case{Unknown::Emission, BasisType::Trilinear, false},
                                           Case{Unknown::Emission, BasisType::Box, false},
                                           Case{Unknown::Albedo, BasisType::Trilinear, false},
                                           Case{Unknown::Albedo, BasisType::Box, false},
                                           Case{Unknown::EmissionAlbedo, BasisType::Trilinear, false},
                                           Case{Unknown::EmissionAlbedo, BasisType::Box, false},
                                           Case{Unknown::Extinction, BasisType::Trilinear, false},
                                           Case{Unknown::Extinction, BasisType::Box, false},
                                           Case{Unknown::Emission, BasisType::Trilinear, true},
                                           Case{Unknown::Albedo, BasisType::Box, true},
                                           Case{Unknown::Emission, BasisType::Trilinear, false, true},
                                           Case{Unknown::Albedo, BasisType::Box, false, true},
                                           Case{Unknown::EmissionAlbedo, BasisType::Trilinear, false, true}));

TEST(Projector, ColumnsFromTheHostAndFromTheFillPassBothMatchTheOracle) {
    VOLSTYLE_REQUIRE_GL();
    // Issue #40: a CPU rasterizer transposes the rows on the host, a GPU places the columns in the
    // fill pass with atomics; CI runs on the first, so the second is checked here explicitly.
    for (int onHost : {0, 1}) {
        Path path;
        path.cached = true;
        path.columnsOnHost = onHost;
        path.mergeViews = 1;
        checkCase({Unknown::EmissionAlbedo, BasisType::Trilinear, false}, path);
        checkCase({Unknown::Extinction, BasisType::Box, true}, path);
    }
}

TEST(Projector, ProductsOnTheHostAndInTheShaderBothMatchTheOracle) {
    VOLSTYLE_REQUIRE_GL();
    // Issue #40: a CPU rasterizer computes W and Wᵀ from the rows on the host; a GPU runs
    // sparse_project.comp. Both, with every view's rows merged (each view then a range of them)
    // and with each view's own rows.
    for (int onHost : {0, 1})
        for (int merge : {0, 1}) {
            Path path;
            path.cached = true;
            path.productsOnHost = onHost;
            path.mergeViews = merge;
            checkCase({Unknown::EmissionAlbedo, BasisType::Trilinear, false}, path);
            checkCase({Unknown::Extinction, BasisType::Box, true}, path);
            checkCase({Unknown::Albedo, BasisType::Trilinear, false, true}, path);
        }
}

TEST(Projector, ProductsOnTheHostKeepTheSupportsAsTheShaderDoes) {
    VOLSTYLE_REQUIRE_GL();
    // With supports (the solver's constrained pixels and hull), W writes the listed pixels only
    // (the others keep what they hold) and Wᵀ the listed elements only (the others 0): the host's
    // products against sparse_project.comp's, value for value, with the views' rows merged (each
    // view a range of them) and with each view's own (a CPU rasterizer's default).
    Problem prob = makeProblem(7);
    GpuVolume gpu(prob.volume);
    for (bool merge : {true, false}) {
        std::vector<uint32_t> pixels, elements;
        std::map<bool, std::vector<std::vector<float>>> results;
        std::vector<float> fullWa, fullWtr;  // without supports: which pixels and elements have entries
        for (bool onHost : {false, true}) {
            Projector W(test::device(), gpu, prob.lighting, Unknown::EmissionAlbedo, BasisType::Trilinear, prob.volume.dims(), 0.5);
            W.setColumnsOnHost(true);  // the rows mapped, so either can compute from them
            W.setProductsOnHost(onHost);
            W.setMergeViews(merge);
            for (const auto& c : prob.cameras) W.addView(c);
            W.cacheRows(size_t(1) << 30, weightChannels(prob.volume, prob.lighting, Unknown::EmissionAlbedo));
            ASSERT_EQ(W.merged(), merge);
            GpuVector ga(W.elementCount(), "a", true), gr(W.pixelCount(), "r", true), gWa(W.pixelCount(), "Wa", true),
                gWtr(W.elementCount(), "Wtr", true), viewWa(W.pixelCount(), "Wv a", true), viewWtr(W.elementCount(), "Wvt r", true);
            ga.upload(toFloat(randomVector(W.elementCount(), 1)));
            gr.upload(toFloat(randomVector(W.pixelCount(), 2)));
            if (pixels.empty()) {
                for (uint32_t p = 0; p < W.pixelCount(); p += 3) pixels.push_back(p);
                for (uint32_t e = 0; e < W.elementCount(); e += 5) elements.push_back(e);
                W.forward(ga, gWa);
                W.adjoint(gr, gWtr);
                fullWa = gWa.download(), fullWtr = gWtr.download();
            }
            W.setSupports(std::make_shared<Support>(pixels), std::make_shared<Support>(elements));
            gWa.fill(7.0f), viewWa.fill(7.0f);
            W.forward(ga, gWa);
            W.adjoint(gr, gWtr);
            W.forwardView(1, ga, viewWa);
            W.adjointView(1, gr, viewWtr);
            for (const GpuVector* v : {&gWa, &gWtr, &viewWa, &viewWtr}) results[onHost].push_back(v->download());
        }
        const char* names[] = {"W a", "Wᵀ r", "W_1 a", "W_1ᵀ r"};
        for (size_t k = 0; k < 4; ++k) {
            const auto &shader = results[false][k], &host = results[true][k];
            ASSERT_EQ(shader.size(), host.size());
            double peak = 0, worst = 0;
            for (size_t i = 0; i < shader.size(); ++i) peak = std::max(peak, double(std::abs(shader[i])));
            for (size_t i = 0; i < shader.size(); ++i) worst = std::max(worst, double(std::abs(shader[i] - host[i])));
            EXPECT_GT(peak, 0.0) << names[k];
            EXPECT_LE(worst, 1e-6 * peak) << names[k] << (merge ? " (merged)" : " (per view)");  // the same sums in the same order
        }
        // Unlisted pixels that W reaches keep the 7 they held; unlisted elements with entries are 0.
        size_t keptPixels = 0, zeroElements = 0;
        for (size_t p = 0; p < fullWa.size() / 4; ++p)
            if (p % 3 != 0 && fullWa[4 * p] != 0.0f) {
                EXPECT_EQ(results[true][0][4 * p], 7.0f) << p;
                ++keptPixels;
            }
        for (size_t e = 0; e < fullWtr.size() / 4; ++e)
            if (e % 5 != 0 && fullWtr[4 * e] != 0.0f) {
                EXPECT_EQ(results[true][1][4 * e], 0.0f) << e;
                ++zeroElements;
            }
        EXPECT_GT(keptPixels, 100u);
        EXPECT_GT(zeroElements, 100u);
    }
}

TEST(Projector, OnlyAlbedosOperatorComputesLightVolumes) {
    VOLSTYLE_REQUIRE_GL();
    // Issue #40 item 5: emission's and extinction's W hold no in-scattering, so their views' set-up
    // makes no light-depth volumes (emission's made one per light before). What W computes is unchanged:
    // CachedRowsMatchTheOracle and IdentityAndOracle hold the lit problem's emission and extinction
    // operators to the float64 oracle.
    const Problem prob = makeProblem(11);
    for (Unknown u : {Unknown::Emission, Unknown::Extinction, Unknown::Albedo, Unknown::EmissionAlbedo}) {
        GpuVolume gpu(prob.volume);  // fresh: nothing cached from another operator
        Projector W(test::device(), gpu, prob.lighting, u, BasisType::Trilinear, prob.volume.dims(), 0.5);
        for (const auto& c : prob.cameras) W.addView(c);
        const bool lit = u == Unknown::Albedo || u == Unknown::EmissionAlbedo;
        EXPECT_EQ(W.stats().lightVolumes, lit ? int(prob.lighting.lights.size()) : 0) << "unknown " << int(u);
    }
}

TEST(Projector, CompareAndSwapFallbackIsExactToo) {
    VOLSTYLE_REQUIRE_GL();
    checkCase({Unknown::EmissionAlbedo, BasisType::Trilinear, false}, {false});
}

TEST(Projector, ViewsPastTheCacheBudgetStayMatrixFree) {
    VOLSTYLE_REQUIRE_GL();
    // Room for all but the last view's rows: that one runs matrix-free; the sum is still W.
    Problem prob = makeProblem(7);
    GpuVolume gpu(prob.volume);
    Projector all(test::device(), gpu, prob.lighting, Unknown::Albedo, BasisType::Trilinear, prob.volume.dims(), 0.5);
    for (const auto& c : prob.cameras) all.addView(c);
    all.setMergeViews(true);
    all.keepViewRowsWithin(SIZE_MAX);  // each view's own rows kept beside the merged ones, to measure them
    all.cacheRows(size_t(1) << 30, 3);
    ASSERT_EQ(all.stats().cachedViews, 2u);
    EXPECT_TRUE(all.merged());  // both views' rows as one, within the budget
    size_t views = 0;
    for (size_t v = 0; v < 2; ++v) {
        const auto r = all.rowsOf(v);
        views += sparseRowsBytes(r->rows, r->columns, r->entries, r->channels);
    }
    checkCase({Unknown::Albedo, BasisType::Trilinear, false}, {true, true, views - 1, 1});
}

TEST(Projector, EmissionForwardIsTheRenderersEmission) {
    VOLSTYLE_REQUIRE_GL();
    // W a with a = the emission grid renders what the renderer renders for emission alone.
    Problem prob = makeProblem(3);
    Volume v = prob.volume;
    auto& e = v.ensureEmission();
    std::mt19937 rng(5);
    for (float& x : e) x = float(rng() % 1000) / 1000.0f;
    GpuVolume gpu(v);
    Lighting dark;
    dark.lights.clear();
    Projector W(test::device(), gpu, dark, Unknown::Emission, BasisType::Trilinear, v.dims(), 0.5);
    W.addView(prob.cameras[0]);
    std::vector<float> a(v.voxelCount() * 4, 0.0f);
    for (size_t i = 0; i < v.voxelCount(); ++i)
        for (int c = 0; c < 3; ++c) a[4 * i + size_t(c)] = e[3 * i + size_t(c)];
    GpuVector ga(W.elementCount(), "a"), out(W.pixelCount(), "Wa");
    ga.upload(a);
    W.forward(ga, out);
    auto Wa = out.download();
    RenderSettings exact;
    exact.terminationThreshold = 0;
    Image img = test::sharedRenderer().render(gpu, prob.cameras[0], dark, exact);
    for (size_t i = 0; i < img.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(Wa[4 * i + size_t(c)], img.rgba[4 * i + size_t(c)], 1e-5f) << i;
}

TEST(Projector, ExactTraversalKeepsTheAdjointIdentity) {
    VOLSTYLE_REQUIRE_GL();
    Problem prob = makeProblem(11);
    GpuVolume gpu(prob.volume);
    for (Unknown u : {Unknown::Emission, Unknown::Albedo, Unknown::Extinction})
        for (BasisType basis : {BasisType::Box, BasisType::Trilinear}) {
            Projector W(test::device(), gpu, prob.lighting, u, basis, prob.volume.dims(), 0.5, /*exact=*/true);
            for (const auto& c : prob.cameras) W.addView(c);
            auto a = randomVector(W.elementCount(), 3), r = randomVector(W.pixelCount(), 4);
            GpuVector ga(W.elementCount(), "a"), gr(W.pixelCount(), "r"), gWa(W.pixelCount(), "Wa"), gWtr(W.elementCount(), "Wtr");
            ga.upload(toFloat(a));
            gr.upload(toFloat(r));
            W.forward(ga, gWa);
            W.adjoint(gr, gWtr);
            Vec3d lhs = dot(r, gWa.download()), rhs = dot(a, gWtr.download());
            for (int c = 0; c < 3; ++c)
                EXPECT_LE(std::abs(lhs[c] - rhs[c]) / std::max(std::abs(lhs[c]), 1e-3), 1e-4)
                    << "unknown " << int(u) << " basis " << int(basis) << " channel " << c;
        }
}

TEST(Projector, ForwardByColumnsIsTheRowGatherOnASparseVector) {
    VOLSTYLE_REQUIRE_GL();
    // W c for a c that is 0 but at a few unknowns (a projected step's clamped ones), by the columns
    // (only those read, added atomically) against the row gather over all of W, with float atomics
    // and with the compare-and-swap loop.
    Problem prob = makeProblem(7);
    GpuVolume gpu(prob.volume);
    for (bool floatAtomics : {true, false}) {
        if (floatAtomics && !test::device().capabilities().hasFloatAtomics) continue;
        Projector W(test::device(), gpu, prob.lighting, Unknown::EmissionAlbedo, BasisType::Trilinear, prob.volume.dims(), 0.5);
        W.setUseFloatAtomics(floatAtomics);
        W.setMergeViews(true);  // two views: by columns needs their rows merged
        for (const auto& c : prob.cameras) W.addView(c);
        W.cacheRows(size_t(1) << 30, weightChannels(prob.volume, prob.lighting, Unknown::EmissionAlbedo));
        ASSERT_TRUE(W.canForwardByColumns());
        std::vector<double> c(W.elementCount() * 4, 0.0);
        const auto noise = randomVector(W.elementCount(), 3);
        for (size_t e = 0; e < W.elementCount(); e += 37)
            for (int k = 0; k < 3; ++k) c[4 * e + size_t(k)] = noise[4 * e + size_t(k)];
        GpuVector gc(W.elementCount(), "c"), byRows(W.pixelCount(), "rows"), byColumns(W.pixelCount(), "columns");
        gc.upload(toFloat(c));
        W.forward(gc, byRows);
        W.forwardByColumns(gc, byColumns);
        const auto want = byRows.download(), got = byColumns.download();
        double peak = 0, worst = 0;
        for (size_t i = 0; i < want.size(); ++i) peak = std::max(peak, double(std::abs(want[i])));
        for (size_t i = 0; i < want.size(); ++i) worst = std::max(worst, double(std::abs(want[i] - got[i])));
        EXPECT_GT(peak, 0.0);
        EXPECT_LE(worst, 1e-5 * peak) << (floatAtomics ? "float atomics" : "compare-and-swap");
    }
}

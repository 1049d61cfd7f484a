// Curved rays through a refractive_index grid (issue #16): a constant index leaves renders and
// solves bit for bit those of the straight path; W and Wᵀ follow the same refracted paths (the
// adjoint identity to 1e-4 for every unknown); the march integrates along the traced polyline
// (a constant medium gives 1 − e^{−σ·length} of each pixel's own path); and the paper's Fig. 8
// case — extinction through a glass sphere from four views — recovers its targets.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include "core/render/curved_paths.h"
#include "core/render/refracted_paths.h"
#include "core/solve/projector.h"
#include "core/solve/sparse_rows.h"
#include "core/solve/solver.h"
#include "core/volume/builtin_scenes.h"
#include "../common/mask_solve.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A noisy emissive, scattering medium (odd sizes: see projector_test.cpp).
Volume noisyMedium(Int3 dims, uint32_t seed) {
    Volume v(dims, unitBoxWorldFromIndex(dims));
    std::mt19937 rng(seed);
    auto u = [&] { return float(rng() % 100000) / 100000.0f; };
    auto& e = v.ensureEmission();
    auto& a = v.ensureAlbedo();
    for (size_t i = 0; i < v.voxelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            v.extinction()[3 * i + size_t(c)] = u() < 0.2f ? 0.0f : 3.0f * u();
            e[3 * i + size_t(c)] = 0.5f * u();
            a[3 * i + size_t(c)] = 0.3f + 0.6f * u();
        }
    return v;
}

Lighting sunAndSky() {
    Lighting l;
    l.lights = {{{0.3, 0.8, 0.2}, {3, 2.5, 2}}};
    l.phase = {PhaseType::HenyeyGreenstein, 0.3};
    l.background.color = {0.2, 0.3, 0.5};
    return l;
}

std::vector<Camera> ring(int count, int size, double radius = 2.8) {
    std::vector<Camera> cams;
    for (int i = 0; i < count; ++i) {
        const double a = 0.3 + 2 * std::numbers::pi * i / count;
        Camera c;
        c.eye = {radius * std::sin(a) + 0.0137, 0.35 * std::cos(3 * a) + 0.0071, radius * std::cos(a)};
        c.target = {0.0123, -0.0091, 0.0057};
        c.fovYDeg = 45;
        c.width = c.height = size;
        cams.push_back(c);
    }
    return cams;
}

bool bitIdentical(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height && std::memcmp(a.rgba.data(), b.rgba.data(), a.rgba.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(Refraction, AConstantIndexIsTheStraightPathBitForBit) {
    VOLSTYLE_REQUIRE_GL();
    const Volume plain = noisyMedium({13, 11, 15}, 3);
    const Lighting l = sunAndSky();
    const Camera cam = ring(1, 24)[0];
    GpuVolume straight(plain);
    const Image reference = test::sharedRenderer().render(straight, cam, l);
    for (float n : {1.0f, 1.33f}) {
        Volume constant = plain;
        constant.refractiveIndex() = std::vector<float>(plain.voxelCount(), n);
        GpuVolume gpu(constant);
        EXPECT_FALSE(gpu.refraction()) << "a constant index bends nothing: no paths are traced";
        RenderStats stats;
        EXPECT_TRUE(bitIdentical(test::sharedRenderer().render(gpu, cam, l, {}, &stats), reference)) << "n = " << n;
        EXPECT_EQ(stats.refractionMs, 0.0);
    }
    // W: the same kernel, so the same values bit for bit (Wᵀ and the solve add with atomics, whose
    // order varies from run to run even on the straight path: they agree to rounding).
    Volume constant = plain;
    constant.refractiveIndex() = std::vector<float>(plain.voxelCount(), 1.0f);
    GpuVolume gpuConstant(constant);
    Projector straightW(test::device(), straight, l, Unknown::Albedo, BasisType::Trilinear, plain.dims(), 0.5);
    Projector constantW(test::device(), gpuConstant, l, Unknown::Albedo, BasisType::Trilinear, plain.dims(), 0.5);
    straightW.addView(cam);
    constantW.addView(cam);
    std::vector<float> a(straightW.elementCount() * 4, 0.5f);
    GpuVector ga(straightW.elementCount(), "a"), w1(straightW.pixelCount(), "w1"), w2(straightW.pixelCount(), "w2");
    ga.upload(a);
    straightW.forward(ga, w1);
    constantW.forward(ga, w2);
    const auto f1 = w1.download(), f2 = w2.download();
    EXPECT_EQ(std::memcmp(f1.data(), f2.data(), f1.size() * sizeof(float)), 0);

    std::vector<SolveView> views{{"v", cam, reference, std::nullopt}};
    SolveOptions opt;
    opt.unknown = Unknown::Emission;
    opt.maxIterations = 4;
    Volume start = plain;
    start.emission().assign(start.emission().size(), 0.0f);
    const SolveResult s1 = Solver(test::device(), start, l, views, opt).run();
    start.refractiveIndex() = std::vector<float>(plain.voxelCount(), 1.0f);
    const SolveResult s2 = Solver(test::device(), start, l, views, opt).run();
    double worst = 0, peak = 0;
    for (size_t i = 0; i < s1.volume.emission().size(); ++i) {
        worst = std::max(worst, double(std::abs(s1.volume.emission()[i] - s2.volume.emission()[i])));
        peak = std::max(peak, double(std::abs(s1.volume.emission()[i])));
    }
    EXPECT_GT(peak, 0.0);
    EXPECT_LE(worst, 1e-5 * peak);
    EXPECT_EQ(s1.report.iterations, s2.report.iterations);
}

TEST(Refraction, TheAdjointIdentityHoldsOnCurvedRays) {
    VOLSTYLE_REQUIRE_GL();
    Volume v = noisyMedium({13, 11, 15}, 5);
    addGlassSphere(v, {1.4, 0.6, 2, 0.05, 3, 2});
    const Lighting l = sunAndSky();
    const auto cams = ring(2, 16);
    for (Unknown unknown : {Unknown::Emission, Unknown::Albedo, Unknown::EmissionAlbedo, Unknown::Extinction})
        for (BasisType basis : {BasisType::Trilinear, BasisType::Box})
            for (bool cached : {false, true}) {
                GpuVolume gpu(v);
                ASSERT_TRUE(gpu.refraction());
                Projector W(test::device(), gpu, l, unknown, basis, v.dims(), 0.5);
                for (const auto& c : cams) W.addView(c);
                if (cached) W.cacheRows(size_t(1) << 28, weightChannels(v, l, unknown));
                std::mt19937 rng(11);
                auto rnd = [&] { return float(rng() % 200001) / 100000.0f - 1.0f; };
                std::vector<float> a(W.elementCount() * 4, 0.0f), r(W.pixelCount() * 4, 0.0f);
                for (size_t i = 0; i < a.size(); ++i) a[i] = i % 4 == 3 ? 0.0f : rnd();
                for (size_t i = 0; i < r.size(); ++i) r[i] = i % 4 == 3 ? 0.0f : rnd();
                GpuVector ga(W.elementCount(), "a"), gr(W.pixelCount(), "r"), gWa(W.pixelCount(), "Wa"), gWtr(W.elementCount(), "Wtr");
                ga.upload(a);
                gr.upload(r);
                W.forward(ga, gWa);
                W.adjoint(gr, gWtr);
                const auto Wa = gWa.download(), Wtr = gWtr.download();
                for (int c = 0; c < 3; ++c) {
                    double lhs = 0, rhs = 0;
                    for (size_t i = size_t(c); i < r.size(); i += 4) lhs += double(r[i]) * Wa[i];
                    for (size_t i = size_t(c); i < a.size(); i += 4) rhs += double(a[i]) * Wtr[i];
                    EXPECT_GT(std::abs(lhs), 1e-3);
                    EXPECT_LE(std::abs(lhs - rhs) / std::max(std::abs(lhs), 1e-3), 1e-4)
                        << "unknown " << int(unknown) << " basis " << int(basis) << (cached ? " rows" : " matrix-free") << " channel " << c;
                }
            }
}

TEST(Refraction, TheMarchIntegratesAlongEachPixelsPath) {
    VOLSTYLE_REQUIRE_GL();
    // Constant σ and emission L fill the box, no lights: a pixel's radiance is
    // L (1 − e^{−σ ℓ}) + B e^{−σ ℓ}, ℓ its own path's length in the box (CPU-traced polyline).
    const Int3 dims{24, 24, 24};
    Volume v(dims, unitBoxWorldFromIndex(dims));
    const float sigma = 0.8f, L = 1.0f;
    v.extinction().assign(v.voxelCount() * 3, sigma);
    v.ensureEmission().assign(v.voxelCount() * 3, L);
    addGlassSphere(v, {1.5, 0.6, 2, 0.04, 3, 4});
    Lighting l;
    l.lights.clear();
    l.background.color = {0.1, 0.1, 0.1};
    Camera cam = ring(1, 20, 3.2)[0];
    GpuVolume gpu(v);
    RenderStats stats;
    const Image img = test::sharedRenderer().render(gpu, cam, l, {}, &stats);
    EXPECT_GT(stats.refractionMs, 0.0);
    const auto grid = RefractiveGrid::of(v);
    double worst = 0, longest = 0, straightest = 1e9;
    int bent = 0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const auto path = traceViewPath(*grid, cam.eye, cam.rayDirection(x, y), cam.nearDist, cam.farDist);
            const double len = path.empty() ? 0.0 : double(path.back().t - path.front().t);
            const double want = L * (1 - std::exp(-sigma * len)) + 0.1 * std::exp(-sigma * len);
            worst = std::max(worst, std::abs(double(img.pixel(x, y)[0]) - want));
            longest = std::max(longest, len);
            if (path.size() > 2) ++bent;
            // The chord from entry to exit is shorter than the bent path.
            if (path.size() >= 2) {
                const Vec3d a(path.front().x, path.front().y, path.front().z), b(path.back().x, path.back().y, path.back().z);
                straightest = std::min(straightest, len - length(v.worldFromIndex().applyVector(b - a)) + 1.0);
            }
        }
    std::cout << "[ measured ] curved march vs 1 − e^{−σℓ} on each pixel's own path: max error " << worst << ", " << bent
              << " bent rays, longest path " << longest << "\n";
    EXPECT_GT(bent, 50);
    EXPECT_GE(straightest, 1.0 - 1e-4) << "no path is shorter than its chord";
    EXPECT_LE(worst, 2e-4);
}

TEST(Refraction, ExtinctionThroughAGlassSphereFromFourViews) {
    VOLSTYLE_REQUIRE_GL();
    // The paper's Fig. 8: a cloud behind and inside a refracting sphere, seen from four views; the
    // extinction is solved through the curved rays (masks of a constant medium radiance).
    const int res = 24;
    Volume truth = makeBuiltinScene("sphere", res);
    addGlassSphere(truth, {1.3, 0.7, 2, 0.04, 3, 7});
    const Vec3d Lm{1.0, 0.9, 0.8};
    test::fillEmission(truth, Lm);
    Lighting l;
    l.lights.clear();
    l.background.color = {0.1, 0.2, 0.5};
    GpuVolume gpu(truth);
    std::vector<SolveView> views;
    for (const Camera& c : ring(4, 32)) views.push_back({"v" + std::to_string(views.size() + 1), c, test::sharedRenderer().render(gpu, c, l), std::nullopt});
    auto [start, opt] = test::maskSolve(truth, Lm);
    const SolveResult r = Solver(test::device(), start, l, views, opt).run();
    double first = 0, last = 0;
    for (size_t i = 0; i < r.report.initialRms.size(); ++i) first += r.report.initialRms[i] / double(r.report.initialRms.size());
    for (size_t i = 0; i < r.report.finalRms.size(); ++i) last += r.report.finalRms[i] / double(r.report.finalRms.size());
    std::cout << "[ measured ] Fig. 8 extinction through glass: " << r.report.iterations << " iterations, RMS " << first << " -> " << last
              << " (" << 100 * last / first << "% of the start)\n";
    EXPECT_LE(last, 0.01 * first);
    // The same targets solved with straight rays cannot match as well: refraction matters here.
    Volume straightStart = start;
    straightStart.refractiveIndex().reset();
    const SolveResult s = Solver(test::device(), straightStart, l, views, opt).run();
    double straightLast = 0;
    for (size_t i = 0; i < s.report.finalRms.size(); ++i) straightLast += s.report.finalRms[i] / double(s.report.finalRms.size());
    std::cout << "[ measured ] the same with straight rays: RMS " << straightLast << "\n";
    EXPECT_GT(straightLast, 2 * last);
}

TEST(Refraction, ASparseVolumeBendsRaysAsTheDenseOneInRendersAndSolves) {
    VOLSTYLE_REQUIRE_GL();
    // Issue #39: a sparse volume's refractive_index grid is traced through its bricks (inactive
    // ones read the background index, 1) — the same paths, so the same pictures and the same solve.
    const int res = 32;
    Volume dense = makeBuiltinScene("cloud", res);
    auto& e = dense.ensureEmission();  // glowing where the smoke is: empty corners stay background
    for (size_t i = 0; i < dense.voxelCount(); ++i)
        if (dense.extinction()[3 * i] > 0) e[3 * i] = 1.0f, e[3 * i + 1] = 0.9f, e[3 * i + 2] = 0.8f;
    Volume sparse = dense.toSparse({3, 5, 1});
    const GlassSphere glass{1.3, 0.7, 2, 0.04, 3, 7};
    addGlassSphere(dense, glass);
    addGlassSphere(sparse, glass);  // into the bricks the glass reaches
    ASSERT_TRUE(sparse.isSparse());
    ASSERT_LT(sparse.bricks()->activeBricks(), size_t(sparse.bricks()->brickDims().volume())) << "the corners are empty";
    EXPECT_EQ(*sparse.toDense().refractiveIndex(), *dense.refractiveIndex());
    GpuVolume gd(dense), gs(sparse);
    ASSERT_TRUE(gs.refraction());
    const Lighting l = sunAndSky();
    std::vector<SolveView> views;
    double worst = 0, peak = 0, bent = 0;
    for (const Camera& c : ring(2, 32)) {
        const Image a = test::sharedRenderer().render(gd, c, l), b = test::sharedRenderer().render(gs, c, l);
        Volume straight = dense;
        straight.refractiveIndex().reset();
        GpuVolume gStraight(straight);
        const Image s = test::sharedRenderer().render(gStraight, c, l);
        for (size_t i = 0; i < a.rgba.size(); ++i) {
            peak = std::max(peak, double(a.rgba[i]));
            worst = std::max(worst, double(std::abs(a.rgba[i] - b.rgba[i])));
            bent = std::max(bent, double(std::abs(a.rgba[i] - s.rgba[i])));
        }
        views.push_back({"v" + std::to_string(views.size()), c, a, std::nullopt});
    }
    std::cout << "[ measured ] refraction through bricks vs dense: " << worst / peak << " of the peak (straight rays differ by " << bent / peak
              << ")\n";
    EXPECT_GT(bent, 0.05 * peak) << "the glass bends the rays";
    EXPECT_LE(worst, 1e-6 * peak);

    // Emission solved through the bent rays toward brighter targets: the same voxels either way.
    for (SolveView& v : views)
        for (float& x : v.target.rgba) x *= 1.2f;
    SolveOptions opt;
    opt.maxIterations = 15;
    opt.coarseIterations = 0;  // (a dense solve's coarse start has no sparse counterpart)
    const SolveResult d = Solver(test::device(), dense, l, views, opt).run();
    const SolveResult s = Solver(test::device(), sparse, l, views, opt).run();
    ASSERT_TRUE(s.volume.isSparse());
    const Volume back = s.volume.toDense();
    double peakE = 0, worstE = 0;
    for (size_t i = 0; i < back.emission().size(); ++i)
        peakE = std::max(peakE, double(d.volume.emission()[i])), worstE = std::max(worstE, double(std::abs(back.emission()[i] - d.volume.emission()[i])));
    std::cout << "[ measured ] sparse vs dense emission solve through glass: RMS " << s.report.finalRms[0] << " vs " << d.report.finalRms[0]
              << ", largest voxel difference " << worstE / peakE << " of the peak\n";
    EXPECT_LT(d.report.finalRms[0], 0.5 * d.report.initialRms[0]);
    EXPECT_LE(worstE, 1e-3 * peakE);  // the same sums in another order (float32 atomics)
}

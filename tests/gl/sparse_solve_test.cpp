// The solver on sparse volumes (issue #39): the unknowns are the stored voxels of the active bricks
// and a one-brick apron; W and Wᵀ find them through the brick table and the Laplacian its
// neighbours across brick borders. The adjoint identity holds, and a sparse solve is the dense solve.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>
#include <random>

#include "../common/stamped_cloud.h"
#include "core/render/gpu_volume.h"
#include "core/solve/gpu_vector.h"
#include "core/solve/projector.h"
#include "core/solve/solver.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

std::vector<Camera> twoViews(int size) {
    std::vector<Camera> cams;
    for (int i = 0; i < 2; ++i) {
        Camera c;
        const double a = 0.4 + 1.9 * i;
        c.eye = {3.0 * std::sin(a), 0.5 - 0.7 * i + 0.013, 3.0 * std::cos(a)};
        c.target = {0.011, -0.03, 0.013};
        c.fovYDeg = 40;
        c.width = c.height = size;
        cams.push_back(c);
    }
    return cams;
}

Vec3d dot(const std::vector<float>& a, const std::vector<float>& b) {
    Vec3d s(0.0);
    for (size_t i = 0; i < a.size(); i += 4)
        for (int c = 0; c < 3; ++c) s[c] += double(a[i + size_t(c)]) * double(b[i + size_t(c)]);
    return s;
}

std::vector<float> randomVector(size_t elements, uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<float> v(elements * 4, 0.0f);
    for (size_t i = 0; i < elements; ++i)
        for (int c = 0; c < 3; ++c) v[4 * i + size_t(c)] = float(rng() % 200001) / 100000.0f - 1.0f;
    return v;
}

}  // namespace

TEST(SparseSolve, TheAdjointIdentityHoldsOnBricksAndWIsTheDenseW) {
    VOLSTYLE_REQUIRE_GL();
    const Volume dense = test::thinCloud(20);
    const Volume sparse = dense.toSparse({3, 1, 5});
    ASSERT_LT(sparse.bricks()->activeBricks(), size_t(sparse.bricks()->brickDims().volume()));
    Lighting l = defaultLighting();
    const auto cams = twoViews(24);
    for (Unknown unknown : {Unknown::Emission, Unknown::Albedo, Unknown::Extinction}) {
        GpuVolume gs(sparse), gd(dense);
        Projector Ws(test::device(), gs, l, unknown, BasisType::Trilinear, sparse.dims(), 0.5);
        Projector Wd(test::device(), gd, l, unknown, BasisType::Trilinear, dense.dims(), 0.5);
        Ws.useSparseUnknowns(*sparse.bricks());
        for (const auto& c : cams) Ws.addView(c), Wd.addView(c);
        ASSERT_EQ(Ws.elementCount(), sparse.storedVoxels());
        // a over the stored voxels, 0 in the background brick; the dense a holds the same values.
        std::vector<float> as = randomVector(Ws.elementCount(), 1);
        std::fill(as.begin(), as.begin() + 4 * kBrickVoxels, 0.0f);
        std::vector<float> ad(4 * dense.voxelCount(), 0.0f);
        forEachActiveVoxel(sparse, [&](Int3 p, size_t s) { std::copy_n(as.begin() + std::ptrdiff_t(4 * s), 4, ad.begin() + std::ptrdiff_t(4 * dense.index(p.x, p.y, p.z))); });
        const std::vector<float> r = randomVector(Ws.pixelCount(), 2);
        GpuVector ga(Ws.elementCount(), "a"), gad(Wd.elementCount(), "a-dense"), gr(Ws.pixelCount(), "r");
        GpuVector wa(Ws.pixelCount(), "Wa"), wad(Wd.pixelCount(), "Wa-dense"), wtr(Ws.elementCount(), "Wtr");
        ga.upload(as), gad.upload(ad), gr.upload(r);
        Ws.forward(ga, wa);
        Wd.forward(gad, wad);
        Ws.adjoint(gr, wtr);
        const std::vector<float> Wa = wa.download(), Wad = wad.download(), Wtr = wtr.download();
        const Vec3d lhs = dot(r, Wa), rhs = dot(as, Wtr);
        double peak = 0, worst = 0;
        for (size_t i = 0; i < Wa.size(); ++i) peak = std::max(peak, double(std::abs(Wad[i]))), worst = std::max(worst, double(std::abs(Wa[i] - Wad[i])));
        std::cout << "[ measured ] unknown " << int(unknown) << ": identity " << std::abs(lhs.x - rhs.x) / std::abs(lhs.x)
                  << ", |W_sparse a - W_dense a| " << worst / peak << " of the peak\n";
        for (int c = 0; c < 3; ++c) EXPECT_LE(std::abs(lhs[c] - rhs[c]) / std::max(std::abs(lhs[c]), 1e-3), 1e-4) << int(unknown);
        EXPECT_GT(peak, 0.0);
        EXPECT_LE(worst, 1e-5 * peak) << int(unknown);
    }
}

TEST(SparseSolve, SolvingEmissionOnBricksGivesTheDenseSolution) {
    VOLSTYLE_REQUIRE_GL();
    const Volume plain = test::thinCloud(24);
    Volume truth = plain;
    test::stampLetters(truth, truth.ensureEmission(), Vec3(2.0f, 1.0f, 0.2f));
    const Lighting l = defaultLighting();
    std::vector<SolveView> views;
    GpuVolume gt(truth);
    const auto cams = twoViews(32);
    for (size_t i = 0; i < cams.size(); ++i) views.push_back({"v" + std::to_string(i), cams[i], test::sharedRenderer().render(gt, cams[i], l), std::nullopt});
    SolveOptions opt;
    opt.maxIterations = 40;
    opt.coarseIterations = 0;  // (a dense solve's coarse start has no sparse counterpart)
    const Volume sparseStart = plain.toSparse({5, 2, 7});
    const SolveResult d = Solver(test::device(), plain, l, views, opt).run();
    const SolveResult s = Solver(test::device(), sparseStart, l, views, opt).run();
    ASSERT_TRUE(s.volume.isSparse());
    // The apron: bricks next to the active ones joined the unknowns.
    EXPECT_GT(s.volume.bricks()->activeBricks(), sparseStart.bricks()->activeBricks());
    EXPECT_EQ(s.report.hullCount, d.report.hullCount);
    EXPECT_EQ(s.report.iterations, d.report.iterations);
    const Volume back = s.volume.toDense();
    double peak = 0, worst = 0;
    for (size_t i = 0; i < back.emission().size(); ++i)
        peak = std::max(peak, double(d.volume.emission()[i])), worst = std::max(worst, double(std::abs(back.emission()[i] - d.volume.emission()[i])));
    std::cout << "[ measured ] sparse vs dense emission solve: " << s.report.iterations << " iterations each, RMS "
              << s.report.finalRms[0] << " vs " << d.report.finalRms[0] << ", largest voxel difference " << worst / peak << " of the peak\n";
    EXPECT_GT(peak, 0.5);
    // The same sums in another order (float32 atomics and reductions): 1e-3 of the peak.
    EXPECT_LE(worst, 1e-3 * peak);
    EXPECT_NEAR(s.report.finalRms[0], d.report.finalRms[0], 1e-3 * d.report.initialRms[0]);

    // At half the resolution the unknowns are coarser bricks over the same region: the dense
    // solve at that resolution again, once interpolated back onto the voxels.
    SolveOptions half = opt;
    half.resolution = Int3{12, 12, 12};
    const SolveResult dh = Solver(test::device(), plain, l, views, half).run();
    const SolveResult sh = Solver(test::device(), sparseStart, l, views, half).run();
    EXPECT_EQ(sh.report.hullCount, dh.report.hullCount);
    const Volume backHalf = sh.volume.toDense();
    double peakH = 0, worstH = 0;
    forEachActiveVoxel(sh.volume, [&](Int3 p, size_t) {
        const size_t i = 3 * plain.index(p.x, p.y, p.z);
        if (plain.extinction()[i] <= 0) return;  // where the emission shows (σt·Le)
        for (int c = 0; c < 3; ++c) {
            peakH = std::max(peakH, double(dh.volume.emission()[i + size_t(c)]));
            worstH = std::max(worstH, double(std::abs(backHalf.emission()[i + size_t(c)] - dh.volume.emission()[i + size_t(c)])));
        }
    });
    std::cout << "[ measured ] at 12³ unknowns: " << sh.report.iterations << " iterations, largest voxel difference " << worstH / peakH << " of the peak\n";
    EXPECT_GT(peakH, 0.5);
    EXPECT_LE(worstH, 1e-3 * peakH);
}

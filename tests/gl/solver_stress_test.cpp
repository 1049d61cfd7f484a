// Numerical stability (SPEC §5): extreme inputs finish with finite values, a non-increasing
// objective and a stated reason — never NaN/Inf, never a crash.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/base/errors.h"
#include "core/render/gpu_volume.h"
#include "core/solve/solver.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

std::vector<Camera> twoCameras(int size) {
    Camera a, b;
    a.eye = {0.013, 0.21, 3.0};
    b.eye = {3.0, 0.37, 0.019};
    for (Camera* c : {&a, &b}) c->target = {0.01, -0.02, 0.015}, c->width = c->height = size, c->fovYDeg = 45;
    return {a, b};
}

Image constantImage(int size, Vec3 rgb, float alpha = 1) {
    Image img(size, size);
    for (size_t i = 0; i < img.pixelCount(); ++i)
        img.rgba[4 * i] = rgb.x, img.rgba[4 * i + 1] = rgb.y, img.rgba[4 * i + 2] = rgb.z, img.rgba[4 * i + 3] = alpha;
    return img;
}

std::vector<SolveView> views(const std::vector<Camera>& cams, const std::vector<Image>& targets) {
    std::vector<SolveView> v;
    for (size_t i = 0; i < cams.size(); ++i) v.push_back({"v" + std::to_string(i + 1), cams[i], targets[i], std::nullopt});
    return v;
}

/// Runs and checks the invariants every solve must keep.
SolveResult solveChecked(const Volume& vol, const Lighting& l, std::vector<SolveView> vs, SolveOptions opt) {
    opt.maxIterations = std::min(opt.maxIterations, 20);
    SolveResult r = Solver(test::device(), vol, l, std::move(vs), opt).run();
    EXPECT_NE(r.report.stopReason, StopReason::None);
    for (size_t i = 1; i < r.report.objectiveHistory.size(); ++i) {
        EXPECT_TRUE(std::isfinite(r.report.objectiveHistory[i]));
        EXPECT_LE(r.report.objectiveHistory[i], r.report.objectiveHistory[i - 1] * (1 + 1e-6) + 1e-30) << i;
    }
    for (const auto* g : {&r.volume.extinction(), &r.volume.albedo(), &r.volume.emission()})
        for (float x : *g) EXPECT_TRUE(std::isfinite(x));
    EXPECT_NO_THROW(r.volume.validate());
    return r;
}

Volume scaledSphere(float scale) {
    Volume v = makeBuiltinScene("sphere", 16);
    for (float& s : v.extinction()) s *= scale;
    return v;
}

}  // namespace

TEST(SolverStress, ExtinctionFrom1e8To1e6) {
    VOLSTYLE_REQUIRE_GL();
    auto cams = twoCameras(16);
    for (float sigma : {1e-8f, 1e-3f, 1.0f, 1e3f, 1e6f}) {
        Volume v = scaledSphere(sigma / 8);  // the sphere peaks at 8
        for (Unknown u : {Unknown::Emission, Unknown::Albedo}) {
            SolveOptions opt;
            opt.unknown = u;
            auto r = solveChecked(v, defaultLighting(), views(cams, {constantImage(16, {0.5f, 0.4f, 0.3f}), constantImage(16, {0.2f, 0.3f, 0.4f})}), opt);
            std::cout << "[ measured ] σ " << sigma << " " << unknownName(u) << ": " << r.report.stopReason << " after "
                      << r.report.iterations << "\n";
        }
        SolveOptions ext;
        ext.unknown = Unknown::Extinction;
        ext.mediumRadiance = Vec3d(1.0);
        solveChecked(v, defaultLighting(), views(cams, {constantImage(16, {0.6f, 0.7f, 0.9f}), constantImage(16, {0.5f, 0.6f, 0.8f})}), ext);
    }
}

TEST(SolverStress, EmptyVolumeSaysSo) {
    VOLSTYLE_REQUIRE_GL();
    Volume empty({16, 16, 16}, unitBoxWorldFromIndex({16, 16, 16}));
    auto cams = twoCameras(8);
    auto r = solveChecked(empty, defaultLighting(), views(cams, {constantImage(8, Vec3(0.5f)), constantImage(8, Vec3(0.5f))}), {});
    EXPECT_EQ(r.report.stopReason, StopReason::EmptyHull);
    EXPECT_EQ(r.report.iterations, 0);
}

TEST(SolverStress, OneViewWithOnePixel) {
    VOLSTYLE_REQUIRE_GL();
    Camera c = twoCameras(1)[0];
    auto r = solveChecked(scaledSphere(1), defaultLighting(), views({c}, {constantImage(1, {2, 1, 0.5f})}), {});
    EXPECT_EQ(r.report.constraintPixels, 1u);
    EXPECT_LT(r.report.finalObjective, r.report.initialObjective);
}

TEST(SolverStress, InconsistentTargetsSettleBetween) {
    VOLSTYLE_REQUIRE_GL();
    // Two views ask for opposite colours of the same volume: the best fit lies between.
    auto cams = twoCameras(16);
    SolveOptions opt;
    opt.maxIterations = 20;
    auto r = solveChecked(scaledSphere(1), defaultLighting(),
                          views(cams, {constantImage(16, {1, 0, 0}), constantImage(16, {0, 0, 1})}), opt);
    EXPECT_LT(r.report.finalObjective, r.report.initialObjective);
    EXPECT_GT(r.report.finalRms[0], 0.05) << "cannot match both";
}

TEST(SolverStress, UnreachableTargetsStopAtTheBounds) {
    VOLSTYLE_REQUIRE_GL();
    auto cams = twoCameras(16);
    // Brighter than the background-limited emission can reach where the sphere is thin; albedo
    // asked darker than 0 (targets black under a bright sun): albedo stays in [0, 1].
    auto bright = solveChecked(scaledSphere(0.05f), defaultLighting(),
                               views(cams, {constantImage(16, Vec3(50.0f)), constantImage(16, Vec3(50.0f))}), {});
    for (float e : bright.volume.emission()) EXPECT_GE(e, 0.0f);
    SolveOptions albedo;
    albedo.unknown = Unknown::Albedo;
    auto dark = solveChecked(scaledSphere(1), defaultLighting(),
                             views(cams, {constantImage(16, Vec3(0.0f)), constantImage(16, Vec3(0.0f))}), albedo);
    float lo = 1;
    for (float a : dark.volume.albedo()) {
        lo = std::min(lo, a);
        EXPECT_GE(a, 0.0f);
        EXPECT_LE(a, 1.0f);
    }
    EXPECT_EQ(lo, 0.0f) << "the darkest voxels sit on the bound";
}

TEST(SolverStress, ExtremeRegularization) {
    VOLSTYLE_REQUIRE_GL();
    auto cams = twoCameras(16);
    auto vs = views(cams, {constantImage(16, {0.8f, 0.5f, 0.2f}), constantImage(16, {0.8f, 0.5f, 0.2f})});
    for (double w : {0.0, 1e6}) {
        SolveOptions opt;
        opt.regularization = {w, w, w};
        auto r = solveChecked(scaledSphere(1), defaultLighting(), vs, opt);
        std::cout << "[ measured ] regularization " << w << ": " << r.report.stopReason << ", objective "
                  << r.report.initialObjective << " -> " << r.report.finalObjective << "\n";
    }
}

TEST(SolverStress, ExtinctionRatiosOutsideTheLogDomain) {
    VOLSTYLE_REQUIRE_GL();
    // Targets beyond L_m (ratio ≤ 0) get weight 0; brighter than the background (ratio > 1) are
    // clamped; both are counted.
    auto cams = twoCameras(8);
    SolveOptions opt;
    opt.unknown = Unknown::Extinction;
    opt.mediumRadiance = Vec3d(0.5);
    Lighting l = defaultLighting();
    l.background.color = {0.2, 0.2, 0.2};
    auto r = solveChecked(scaledSphere(1), l, views(cams, {constantImage(8, Vec3(0.9f)), constantImage(8, Vec3(0.1f))}), opt);
    EXPECT_EQ(r.report.ignoredPixels, 3u * 64);  // view 1: 0.9 is beyond L_m = 0.5 from L_bg = 0.2
    EXPECT_EQ(r.report.clampedPixels, 3u * 64);  // view 2: 0.1 is further from L_m than L_bg
}

TEST(SolverStress, NanTargetIsRejectedBeforeSolving) {
    VOLSTYLE_REQUIRE_GL();
    auto cams = twoCameras(8);
    Image bad = constantImage(8, Vec3(0.5f));
    bad.pixel(3, 4)[1] = std::numeric_limits<float>::quiet_NaN();
    try {
        Solver(test::device(), scaledSphere(1), defaultLighting(), views(cams, {bad, constantImage(8, Vec3(0.5f))}), {});
        FAIL() << "a NaN target was accepted";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("view 'v1': the target has 1 non-finite"), std::string::npos) << e.what();
    }
}

TEST(SolverStress, BadOptionsAreListed) {
    SolveOptions opt;
    opt.unknown = Unknown::Extinction;  // without medium_radiance
    opt.maxIterations = 0;
    opt.regularization.laplacian = -1;
    auto problems = opt.check();
    ASSERT_EQ(problems.size(), 3u);
    EXPECT_EQ(problems[0].field, "regularization/laplacian");
    EXPECT_EQ(problems[1].field, "max_iterations");
    EXPECT_EQ(problems[2].field, "medium_radiance");
}

TEST(SolverStress, CancelledSolveLeavesNothingBehind) {
    VOLSTYLE_REQUIRE_GL();
    auto cams = twoCameras(16);
    Volume v = scaledSphere(1);
    std::atomic<bool> cancel{false};
    Solver solver(test::device(), v, defaultLighting(), views(cams, {constantImage(16, Vec3(0.7f)), constantImage(16, Vec3(0.7f))}), {});
    int seen = 0;
    EXPECT_THROW(solver.run([&](const SolveProgress&) { if (++seen == 2) cancel = true; }, &cancel), Cancelled);
    EXPECT_EQ(seen, 2);
    EXPECT_FALSE(v.hasEmission());
}

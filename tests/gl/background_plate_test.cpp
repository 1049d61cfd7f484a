// Per-view background plates (SPEC §1): the renderer reads the plate per pixel (against the
// float64 oracle, and exactly where a ray misses the volume), refuses a plate of another size, and
// a solve whose views carry their plates explains the targets that were painted over them.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/base/errors.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/render/gpu_volume.h"
#include "core/solve/solver.h"
#include "../common/stamped_cloud.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A plate with structure in both axes (so a flipped or shifted lookup shows), values in [0.1, 1.1].
std::shared_ptr<const Image> plateFor(const Camera& cam, uint32_t seed) {
    auto plate = std::make_shared<Image>(cam.width, cam.height);
    std::mt19937 rng(seed);
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            float* p = plate->pixel(x, y);
            p[0] = 0.1f + float(x) / float(cam.width);
            p[1] = 0.1f + float(y) / float(cam.height);
            p[2] = 0.1f + float(rng() % 1000) / 1000.0f;
            p[3] = 1;
        }
    return plate;
}

Camera sideCamera(int size, double angle) {
    Camera c;
    c.eye = {3.0 * std::sin(angle), 0.35, 3.0 * std::cos(angle)};
    c.target = {0.011, -0.07, 0.013};
    c.fovYDeg = 45;
    c.width = c.height = size;
    return c;
}

double rmsOf(const std::vector<double>& perView) {
    double s = 0;
    for (double r : perView) s += r;
    return perView.empty() ? 0 : s / double(perView.size());
}

}  // namespace

TEST(BackgroundPlate, RendersBehindTheVolumePerPixel) {
    VOLSTYLE_REQUIRE_GL();
    Volume v = test::thinCloud(16);
    for (float& e : v.ensureEmission()) e = 0.3f;
    Camera cam = sideCamera(24, 0.4);
    cam.width = 28;  // not square: rows and columns cannot be swapped unnoticed
    Lighting l = defaultLighting();
    l.background.plate = plateFor(cam, 7);
    GpuVolume gpu(v);
    const Image gl = test::sharedRenderer().render(gpu, cam, l);
    const Image ref = cpu_ref::renderReference<double>(v, cam, l, 0.5);
    float peak = 0;
    for (float x : ref.rgba) peak = std::max(peak, x);
    EXPECT_LE(test::maxRelativeError(gl, ref, 1e-3 * peak), 1e-4);

    // Where a ray sees no medium (alpha 0), the pixel is the plate's: to its last bits, not
    // exactly, because on NVIDIA e^{−τ} of a τ under ~6e-8 rounds to 1 (alpha 0) while the
    // medium still adds its τ·L (1e-8 here). A swapped row or column is off by far more.
    size_t clear = 0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x)
            if (gl.pixel(x, y)[3] == 0.0f) {
                ++clear;
                for (int c = 0; c < 3; ++c) ASSERT_NEAR(gl.pixel(x, y)[c], l.background.plate->pixel(x, y)[c], 1e-6) << x << "," << y;
            }
    EXPECT_GT(clear, size_t(50));
}

TEST(BackgroundPlate, OfAnotherSizeIsRefused) {
    VOLSTYLE_REQUIRE_GL();
    GpuVolume gpu(test::thinCloud(8));
    Camera cam = sideCamera(16, 0);
    Lighting l;
    Camera other = cam;
    other.width = 17;
    l.background.plate = plateFor(other, 1);
    try {
        test::sharedRenderer().render(gpu, cam, l);
        FAIL() << "a 17x16 plate was accepted for a 16x16 camera";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("17x16"), std::string::npos) << e.what();
    }
}

TEST(BackgroundPlate, SolveExplainsTargetsPaintedOverPlates) {
    VOLSTYLE_REQUIRE_GL();
    const int res = 24;
    Volume plain = test::thinCloud(res);
    Volume truth = plain;
    test::stampLetters(truth, truth.ensureEmission(), Vec3(2.0f, 1.0f, 0.2f));
    Lighting l = defaultLighting();
    GpuVolume gTruth(truth);
    std::vector<SolveView> withPlates, withoutPlates;
    for (int i = 0; i < 4; ++i) {
        SolveView v;
        v.name = "v" + std::to_string(i + 1);
        v.camera = sideCamera(24, 0.3 + std::numbers::pi * i / 2);
        v.background = plateFor(v.camera, 11 + uint32_t(i));
        v.target = test::sharedRenderer().render(gTruth, v.camera, v.lightingFor(l));
        withPlates.push_back(v);
        v.background = nullptr;
        withoutPlates.push_back(v);
    }
    SolveOptions opt;
    opt.regularization.laplacian = 2e-4;
    opt.maxIterations = 80;
    opt.tolerance = 1e-7;
    const SolveResult a = Solver(test::device(), plain, l, withPlates, opt).run();
    const SolveResult b = Solver(test::device(), plain, l, withoutPlates, opt).run();
    std::cout << "[ measured ] plates: RMS " << rmsOf(a.report.initialRms) << " -> " << rmsOf(a.report.finalRms)
              << "; the same targets without their plates: " << rmsOf(b.report.initialRms) << " -> "
              << rmsOf(b.report.finalRms) << "\n";
    EXPECT_LE(rmsOf(a.report.finalRms), 0.02 * rmsOf(a.report.initialRms));
    // Without the plates the background cannot be explained by emission: the fit floors far higher.
    EXPECT_GT(rmsOf(b.report.finalRms), 5 * rmsOf(a.report.finalRms));
}

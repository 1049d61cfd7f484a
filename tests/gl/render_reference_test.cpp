// The GL renderer against the float64 CPU oracle on tiny random volumes: ≤ 1e-4 relative per
// pixel and channel (floor 1e-3 of the image's peak, for pixels near zero). Float32 arithmetic
// and early termination at T < 1e-5 both stay well below that.
#include <gtest/gtest.h>

#include <random>

#include "core/cpu_ref/reference_renderer.h"
#include "core/render/gpu_volume.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

struct Case {
    Int3 dims;
    bool emission, albedo, environment, rotated;
    int lights;
    double step;
    uint32_t seed;
};

Volume randomVolume(const Case& c) {
    Mat4 xf = unitBoxWorldFromIndex(c.dims);
    if (c.rotated) {
        Mat4 rot;
        double a = 0.4, b = std::cos(a), s = std::sin(a);
        rot(0, 0) = b, rot(0, 1) = -s, rot(1, 0) = s, rot(1, 1) = b;
        xf = rot * xf;
    }
    Volume v(c.dims, xf);
    std::mt19937 rng(c.seed);
    auto u = [&] { return float(rng() % 100000) / 100000.0f; };
    for (size_t i = 0; i < v.voxelCount(); ++i) {
        bool empty = u() < 0.3f;  // holes, so skipping and σ = 0 paths run
        for (int ch = 0; ch < 3; ++ch) v.extinction()[3 * i + ch] = empty ? 0.0f : 6.0f * u();
    }
    if (c.albedo)
        for (float& a : v.ensureAlbedo()) a = u();
    if (c.emission)
        for (float& e : v.ensureEmission()) e = 2.0f * u();
    return v;
}

Lighting randomLighting(const Case& c) {
    Lighting l;
    l.lights.clear();
    std::mt19937 rng(c.seed + 100);
    auto u = [&] { return double(rng() % 100000) / 100000.0; };
    for (int i = 0; i < c.lights; ++i)
        l.lights.push_back({{u() - 0.5, u() + 0.2, u() - 0.5}, {1 + 3 * u(), 1 + 3 * u(), 1 + 3 * u()}});
    l.phase = {PhaseType::HenyeyGreenstein, 0.4};
    l.background.color = {0.2, 0.3, 0.5};
    if (c.environment) {
        auto env = std::make_shared<Image>(16, 8);
        for (float& p : env->rgba) p = float(u());
        l.background.environment = env;
    }
    return l;
}

Camera orbitCamera(uint32_t seed) {
    Camera cam;
    double a = 0.7 * seed;
    cam.eye = {2.8 * std::sin(a), 0.9, 2.8 * std::cos(a)};
    cam.target = {0.05, -0.1, 0};
    cam.fovYDeg = 45;
    cam.width = 24;
    cam.height = 20;
    return cam;
}

void compare(const Case& c) {
    Volume v = randomVolume(c);
    Lighting l = randomLighting(c);
    Camera cam = orbitCamera(c.seed);
    RenderSettings settings;
    settings.stepVoxels = c.step;
    GpuVolume gpu(v);
    Image gl = test::sharedRenderer().render(gpu, cam, l, settings);
    Image ref = cpu_ref::renderReference<double>(v, cam, l, c.step);
    float peak = 0;
    for (float x : ref.rgba) peak = std::max(peak, x);
    double err = test::maxRelativeError(gl, ref, 1e-3 * peak);
    EXPECT_LE(err, 1e-4) << "dims " << c.dims << " seed " << c.seed;
    ::testing::Test::RecordProperty("max_relative_error_seed_" + std::to_string(c.seed), std::to_string(err));
    std::cout << "[ measured ] seed " << c.seed << ": max relative error " << err << "\n";
}

}  // namespace

TEST(RenderReference, EmissionOnly) {
    VOLSTYLE_REQUIRE_GL();
    compare({{8, 8, 8}, true, false, false, false, 0, 0.5, 1});
}

TEST(RenderReference, TwoSunsWithAlbedoAndHenyeyGreenstein) {
    VOLSTYLE_REQUIRE_GL();
    compare({{12, 10, 14}, false, true, false, false, 2, 0.5, 2});
}

TEST(RenderReference, EverythingOnARotatedGrid) {
    VOLSTYLE_REQUIRE_GL();
    compare({{16, 11, 9}, true, true, false, true, 3, 0.35, 3});
}

TEST(RenderReference, EnvironmentMapBackgroundAndCoarseSteps) {
    VOLSTYLE_REQUIRE_GL();
    compare({{10, 16, 12}, true, true, true, false, 1, 2.0, 4});
}

TEST(RenderReference, SkippingChangesNothing) {
    VOLSTYLE_REQUIRE_GL();
    // Empty-space skipping only jumps over segments whose extinction is exactly zero.
    Volume cloud = makeBuiltinScene("cloud", 32);
    GpuVolume gpu(cloud);
    Camera cam = orbitCamera(5);
    cam.width = cam.height = 48;
    RenderSettings on, off;
    off.skipEmptySpace = false;
    Lighting l;
    Image a = test::sharedRenderer().render(gpu, cam, l, on);
    Image b = test::sharedRenderer().render(gpu, cam, l, off);
    EXPECT_LE(test::maxRelativeError(a, b, 1e-6), 1e-6);
}

TEST(RenderReference, EarlyTerminationStaysUnder1e4) {
    VOLSTYLE_REQUIRE_GL();
    Volume cloud = makeBuiltinScene("cloud", 32);
    auto& e = cloud.ensureEmission();
    for (size_t i = 0; i < e.size(); ++i) e[i] = 0.5f + 0.5f * float(i % 7) / 7;  // something behind to lose
    GpuVolume gpu(cloud);
    Camera cam = orbitCamera(6);
    cam.width = cam.height = 48;
    RenderSettings early, full;
    full.terminationThreshold = 0;
    Lighting l;
    Image a = test::sharedRenderer().render(gpu, cam, l, early);
    Image b = test::sharedRenderer().render(gpu, cam, l, full);
    double err = test::maxRelativeError(a, b, 1e-3);
    std::cout << "[ measured ] early termination at T < 1e-5: max relative error " << err << "\n";
    EXPECT_LE(err, 1e-4);
}

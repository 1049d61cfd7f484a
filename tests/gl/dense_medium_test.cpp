// Dense media at default settings (issue #34): the built-in cloud at 48³, scaled to hold up to 4
// optical depths a voxel (albedo 0.9), lit from behind, the side and at a grazing angle.
//  - Against a converged single-scattering reference computed independently in float64: view rays
//    marched at 0.1 voxel, the light's optical depth marched from every sample itself at 0.05 voxel
//    (no grid, no cuts). The image's sum within 1% and its relative RMS within 2% (the issue's
//    figures). Before issue #34 this cloud was 0.96 / 5.5% off lit from behind; after its first
//    round, 0.975 / 3.8% from the side at the default step (the view march's midpoint quadrature).
//  - Against the oracle of the same scheme (dense segments cut by their occupancy brick, the light
//    grid read with a Catmull–Rom spline across the beam): ≤ 5e-4 relative per pixel, so the GL
//    path is the scheme the benchmarks measured. (Thin random volumes hold 1e-4: RenderReference.
//    Here float32 sums optical depths up to 12 toward the light; measured 1.1e-4. A sub-segment
//    count that differed would be ~1e-2 off.)
#include <gtest/gtest.h>

#include "core/cpu_ref/agreement.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/render/gpu_volume.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

Volume denseCloud() { return cpu_ref::denseBuiltinScene("cloud", 48, 4.0); }

Camera frontCamera() {
    Camera cam;
    cam.eye = {0.3, 0.4, 2.9};
    cam.target = {0, -0.05, 0};
    cam.fovYDeg = 40;
    cam.width = cam.height = 24;
    return cam;
}

struct Sun {
    const char* name;
    Vec3d direction;
};
const Sun kSuns[] = {{"backlit", {0.15, 0.25, -1}}, {"side", {1, 0.2, 0.1}}, {"grazing", {0.95, 0.12, -0.3}}};

Lighting sunOnly(const Vec3d& direction) {
    Lighting l;
    l.lights = {{direction, {10, 10, 10}}};
    l.background.color = {0, 0, 0};  // the medium's light alone
    return l;
}

}  // namespace

TEST(DenseMedium, DefaultSettingsFollowAConvergedReference) {
    VOLSTYLE_REQUIRE_GL();
    const Volume v = denseCloud();
    GpuVolume gpu(v);
    const Camera cam = frontCamera();
    for (const Sun& sun : kSuns) {
        const Lighting l = sunOnly(sun.direction);
        const Image gl = test::sharedRenderer().render(gpu, cam, l, RenderSettings{});
        const Image converged = cpu_ref::renderReference<double>(v, cam, l, 0.1, cpu_ref::LightDepthMethod::Exact, 0.05);
        const cpu_ref::Agreement e = cpu_ref::agreement(gl, converged);
        std::cout << "[ measured ] dense cloud 48³ (4 optical depths a voxel), sun " << sun.name << ": GL at default settings / converged: sum "
                  << e.sumRatio << ", relative RMS " << e.relativeRms << "\n";
        ::testing::Test::RecordProperty(std::string(sun.name) + "_relative_rms", std::to_string(e.relativeRms));
        EXPECT_NEAR(e.sumRatio, 1.0, 0.01) << sun.name;
        EXPECT_LE(e.relativeRms, 0.02) << sun.name;
    }
}

TEST(DenseMedium, TheGlPathIsTheOraclesScheme) {
    VOLSTYLE_REQUIRE_GL();
    const Volume v = denseCloud();
    GpuVolume gpu(v);
    const Camera cam = frontCamera();
    for (const Sun& sun : kSuns) {
        const Lighting l = sunOnly(sun.direction);
        RenderSettings full;
        full.terminationThreshold = 0;  // the oracle marches every ray to its end
        const Image gl = test::sharedRenderer().render(gpu, cam, l, full);
        const Image ref = cpu_ref::renderReference<double>(v, cam, l, full.stepVoxels);
        float peak = 0;
        for (float x : ref.rgba) peak = std::max(peak, x);
        const double err = test::maxRelativeError(gl, ref, 1e-3 * peak);
        std::cout << "[ measured ] sun " << sun.name << ": GL against the oracle's scheme, max relative error " << err << "\n";
        EXPECT_LE(err, 5e-4) << sun.name;
    }
}

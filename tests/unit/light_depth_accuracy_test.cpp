// The optical depth toward a light, as the renderer gets it (light-aligned grid + a march from
// each sample over its first node spans, issue #34), against the exact light integral: a march from
// each sample itself at a step of 0.05 voxel (the float64 oracle's LightDepthMethod::Exact).
// Absolute bounds, at image level, on clouds dense enough to hold up to 4 optical depths a voxel,
// lit from behind, the side, above and at a grazing angle. Both images march the view ray the
// same way (0.5 voxel), so the difference is the light depth's alone:
//  - the sum of the image within 1%, and its relative RMS within 2% (the figures); looser
//    bounds, each stated with what was measured, for a grazing sun and for media below
//    kDenseVoxelDepth, whose rows across the beam stay a voxel apart.
// Before issue #34 (the grid alone) the dense backlit cloud was 26% off in sum and 29% in RMS.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "core/cpu_ref/agreement.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

struct Sun {
    const char* name;
    Vec3d direction;
    bool grazing;
};

const Sun kSuns[] = {{"backlit", {0.15, 0.25, -1}, false},
                     {"side", {1, 0.2, 0.1}, false},
                     {"overhead", {0, 1, 0}, false},
                     {"grazing", {0.95, 0.12, -0.3}, true}};

/// How far the image's sum may be from 1 and its relative RMS may go.
struct Bounds {
    double sum, rms;
};

/// The built-in scene scaled so that its densest voxel holds `voxelDepth` optical depths.
Volume denseScene(const char* name, int res, double voxelDepth) {
    Volume v = makeBuiltinScene(name, res);
    cpu_ref::scaleToVoxelDepth(v, voxelDepth);
    for (float& a : v.ensureAlbedo()) a = 0.9f;
    return v;
}

void expectAccurate(const char* scene, int res, double voxelDepth, Bounds bounds, Bounds grazing) {
    const Volume v = denseScene(scene, res, voxelDepth);
    Camera cam;
    cam.eye = {0.3, 0.4, 2.9};
    cam.target = {0, -0.05, 0};
    cam.fovYDeg = 40;
    cam.width = cam.height = 32;
    for (const Sun& sun : kSuns) {
        Lighting l;
        l.lights = {{sun.direction, {10, 10, 10}}};
        l.background.color = {0, 0, 0};  // the medium's light alone
        const double step = 0.5;
        const Image grid = cpu_ref::renderReference<double>(v, cam, l, step, cpu_ref::LightDepthMethod::Grid);
        // The exact light integral: its own march at 0.05 voxel from every sample.
        const Image exact = cpu_ref::renderReference<double>(v, cam, l, step, cpu_ref::LightDepthMethod::Exact, 0.05);
        const cpu_ref::Agreement e = cpu_ref::agreement(grid, exact);
        std::cout << "[ measured ] " << scene << " " << res << "³, " << voxelDepth << " optical depths a voxel, sun " << sun.name
                  << ": sum " << e.sumRatio << ", relative RMS " << e.relativeRms << "\n";
        ::testing::Test::RecordProperty(std::string(scene) + "_" + sun.name + "_rms", std::to_string(e.relativeRms));
        const Bounds b = sun.grazing ? grazing : bounds;
        EXPECT_NEAR(e.sumRatio, 1.0, b.sum) << scene << " " << sun.name;
        EXPECT_LE(e.relativeRms, b.rms) << scene << " " << sun.name;
    }
}

}  // namespace

// The bounds (sum 1%, RMS 2%) lit from behind, the side and above (measured 0.995 / 1.0%,
// 1.000 / 1.7%, 1.000 / 0.02%); a grazing sun's shadow edges run along the rows: 0.989 / 2.6%.
TEST(LightDepthAccuracy, DenseCloudAgainstTheExactLightIntegral) { expectAccurate("cloud", 48, 4.0, {0.01, 0.02}, {0.015, 0.03}); }

// Below kDenseVoxelDepth (1 optical depth a voxel) the rows stay a voxel apart, so that the
// built-in cloud at 128³ (0.6) builds its light volume no slower than before issue #34: from the
// side and grazing the grid's interpolation across the beam shows (measured 0.984 / 2.8% and
// 0.980 / 2.9%; rows half a voxel apart would give 0.998 / 0.6%). From behind: 0.995 / 1.3%.
TEST(LightDepthAccuracy, ModerateCloudAgainstTheExactLightIntegral) { expectAccurate("cloud", 32, 0.6, {0.025, 0.035}, {0.025, 0.035}); }

TEST(LightDepthAccuracy, DensePlumeAgainstTheExactLightIntegral) { expectAccurate("plume", 24, 2.0, {0.01, 0.02}, {0.01, 0.02}); }

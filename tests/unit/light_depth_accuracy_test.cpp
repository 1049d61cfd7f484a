// Light-depth volumes on light-aligned grids (issue #10) against the quantity they approximate:
// the optical depth marched from each sample point itself (LightDepthMethod::Exact). Both stored
// schemes interpolate between nodes one voxel apart; the light-aligned grid must be no less
// accurate, at image level, than the per-voxel-centre volume it replaced (which cost O(N^4/3)).
// Float64 oracle renders of the built-in cloud and plume under three sun directions.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "core/cpu_ref/reference_renderer.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// Root-mean-square difference over RGB divided by the RMS of `b`, and the largest difference
/// over the peak of `b`.
std::pair<double, double> errors(const Image& a, const Image& b) {
    double num = 0, den = 0, worst = 0, peak = 0;
    for (size_t i = 0; i < b.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double x = a.rgba[4 * i + c], y = b.rgba[4 * i + c];
            num += (x - y) * (x - y);
            den += y * y;
            worst = std::max(worst, std::abs(x - y));
            peak = std::max(peak, std::abs(y));
        }
    return {std::sqrt(num / den), worst / peak};
}

struct Sun {
    const char* name;
    Vec3d direction;
};

void compareSchemes(const char* scene, int res, const Sun& sun) {
    const Volume v = makeBuiltinScene(scene, res);
    Lighting l;
    l.lights = {{sun.direction, {20, 19, 17}}};
    l.background.color = {0, 0, 0};  // the medium's light alone
    l.phase = {PhaseType::HenyeyGreenstein, 0.25};
    Camera cam;
    cam.eye = {0.3, 0.4, 2.9};
    cam.target = {0, -0.05, 0};
    cam.fovYDeg = 40;
    cam.width = cam.height = 40;
    const Image exact = cpu_ref::renderReference<double>(v, cam, l, 0.5, cpu_ref::LightDepthMethod::Exact);
    const Image grid = cpu_ref::renderReference<double>(v, cam, l, 0.5, cpu_ref::LightDepthMethod::Grid);
    const Image centres = cpu_ref::renderReference<double>(v, cam, l, 0.5, cpu_ref::LightDepthMethod::VoxelCentres);
    const auto [gridRms, gridMax] = errors(grid, exact);
    const auto [centreRms, centreMax] = errors(centres, exact);
    std::cout << "[ measured ] " << scene << " " << res << "³, sun " << sun.name << ": vs per-sample depth, light grid RMS "
              << gridRms << " max " << gridMax << "; voxel centres RMS " << centreRms << " max " << centreMax << "\n";
    ::testing::Test::RecordProperty(std::string(scene) + "_" + sun.name + "_grid_rms", std::to_string(gridRms));
    EXPECT_LE(gridRms, 1.1 * centreRms + 1e-6) << scene << " " << sun.name;
    EXPECT_LE(gridMax, 1.5 * centreMax + 1e-6) << scene << " " << sun.name;
}

const Sun kSuns[] = {{"overhead", {0, 1, 0}}, {"diagonal", {-0.55, 0.65, 0.55}}, {"grazing", {0.95, 0.12, -0.3}}};

}  // namespace

TEST(LightDepthAccuracy, CloudGridIsAtLeastAsAccurateAsVoxelCentres) {
    for (const Sun& sun : kSuns) compareSchemes("cloud", 32, sun);
}

TEST(LightDepthAccuracy, PlumeGridIsAtLeastAsAccurateAsVoxelCentres) {
    for (const Sun& sun : kSuns) compareSchemes("plume", 24, sun);
}

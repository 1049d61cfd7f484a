// What the paint asks that the unknowns cannot give (issue #10, core/solve/reach.h): emission only
// adds light, albedo only scatters less, and the report says which unknowns would reach the paint.
#include <gtest/gtest.h>

#include "core/render/gpu_volume.h"
#include "core/solve/reach.h"
#include "core/volume/builtin_scenes.h"
#include "../common/stamped_cloud.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// One 24² view of `truth` as the painted target.
std::vector<SolveView> paintedFrom(const Volume& truth, const Lighting& lighting) {
    Camera c;
    c.eye = {0, 0.3, 3};
    c.width = c.height = 24;
    GpuVolume gpu(truth);
    return {{"front", c, test::sharedRenderer().render(gpu, c, lighting), std::nullopt}};
}

SolveReport reachOf(const Volume& start, const std::vector<SolveView>& views, const Lighting& lighting, Unknown u) {
    SolveOptions opt;
    opt.unknown = u;
    SolveReport report;
    analyzeReach(test::device(), start, lighting, views, opt, report);
    return report;
}

}  // namespace

TEST(Reach, AGlowIsWithinReachOfEmissionAndADarkeningIsNot) {
    VOLSTYLE_REQUIRE_GL();
    const Lighting lighting = defaultLighting();
    const Volume start = test::thinCloud(20);

    // Paint that adds light (an emitted glow): emission reaches all of it, albedo cannot.
    Volume glow = start;
    test::stampLetters(glow, glow.ensureEmission(), {0.8f, 0.4f, 0.1f});
    const auto glowViews = paintedFrom(glow, lighting);
    const SolveReport byEmission = reachOf(start, glowViews, lighting, Unknown::Emission);
    ASSERT_EQ(byEmission.reach.unreachableRms.size(), 1u);
    EXPECT_LT(byEmission.reach.unreachableRms[0], 1e-4);
    EXPECT_TRUE(byEmission.reach.advice.empty()) << byEmission.reach.advice;
    const SolveReport byAlbedo = reachOf(start, glowViews, lighting, Unknown::Albedo);
    EXPECT_GT(byAlbedo.reach.unreachableRms[0], 1e-2);
    ASSERT_TRUE(byAlbedo.reach.suggestion.has_value()) << byAlbedo.reach.advice;
    EXPECT_NE(*byAlbedo.reach.suggestion, Unknown::Albedo);

    // Paint that darkens (less scattering): out of emission's reach; albedo reaches it.
    Volume dark = start;
    test::stampLetters(dark, dark.ensureAlbedo(), {0.2f, 0.2f, 0.2f});
    const auto darkViews = paintedFrom(dark, lighting);
    const SolveReport darkByEmission = reachOf(start, darkViews, lighting, Unknown::Emission);
    EXPECT_GT(darkByEmission.reach.unreachableRms[0], 1e-2);
    ASSERT_TRUE(darkByEmission.reach.suggestion.has_value());
    EXPECT_NE(darkByEmission.reach.advice.find("only adds light"), std::string::npos) << darkByEmission.reach.advice;
    EXPECT_LT(reachOf(start, darkViews, lighting, Unknown::Albedo).reach.unreachableRms[0], 1e-4);
}

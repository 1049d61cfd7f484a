// Compositing-ready renders (issue #10): the EXR's main RGBA is the medium alone, premultiplied,
// so `over` a black plate equals a render with a black background, and the layers add up.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/image/image_io.h"
#include "core/render/exr_layers.h"
#include "core/base/work_budget.h"
#include "core/render/gpu_volume.h"
#include "core/volume/builtin_scenes.h"
#include "../unit/test_files.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

Camera smallCamera() {
    Camera c;
    c.eye = {0.3, 0.4, 3.2};
    c.width = c.height = 24;
    return c;
}

/// A sun and a bright coloured sky (what the layers must keep out of the medium's light).
Lighting sky(Vec3d colour) {
    Lighting l = defaultLighting();
    l.background.color = colour;
    return l;
}

/// Largest |a − b| over RGB (and alpha when `alpha`).
double maxDifference(const Image& a, const Image& b, bool alpha) {
    double worst = 0;
    for (size_t i = 0; i < a.rgba.size(); ++i)
        if (alpha || i % 4 != 3) worst = std::max(worst, std::abs(double(a.rgba[i]) - double(b.rgba[i])));
    return worst;
}

}  // namespace

TEST(RenderLayers, MediumOverABlackPlateIsTheRenderWithABlackBackground) {
    VOLSTYLE_REQUIRE_GL();
    Volume v = makeBuiltinScene("plume", 20);  // emission and scattering
    GpuVolume gpu(v);
    const RenderLayers layers = test::sharedRenderer().renderLayers(gpu, smallCamera(), sky({0.4, 0.6, 0.9}));
    const Image black = test::sharedRenderer().render(gpu, smallCamera(), sky({0, 0, 0}));
    // over a black plate: medium + (1 − alpha)·0 = medium
    const double overBlack = maxDifference(layers.medium, black, true);
    std::printf("[ measured ] EXR medium over a black plate vs a render with a black background: max difference %g\n", overBlack);
    EXPECT_LE(overBlack, 1e-4);
    // The parts add up: medium = emission + scattering; beauty = medium + transmittance·background.
    double parts = 0, beauty = 0, coverage = 0;
    for (size_t p = 0; p < layers.medium.pixelCount(); ++p) {
        for (int c = 0; c < 3; ++c) {
            const size_t i = 4 * p + size_t(c);
            parts = std::max(parts, double(std::abs(layers.medium.rgba[i] - layers.emission.rgba[i] - layers.scattering.rgba[i])));
            beauty = std::max(beauty, double(std::abs(layers.beauty.rgba[i] - layers.medium.rgba[i] -
                                                       layers.transmittance.rgba[i] * layers.background.rgba[i])));
        }
        coverage = std::max(coverage, double(layers.medium.rgba[4 * p + 3]));
    }
    EXPECT_LE(parts, 1e-5);
    EXPECT_LE(beauty, 1e-5);
    EXPECT_GT(coverage, 0.3) << "the plume is in view";
    double emitted = 0;
    for (float x : layers.emission.rgba) emitted = std::max(emitted, double(x));
    EXPECT_GT(emitted, 0.01) << "the plume emits";
}

TEST(RenderLayers, TheAlbedoOneLayerIsTheScatteringOfAWhiteVolume) {
    VOLSTYLE_REQUIRE_GL();
    // Issue #40: the reach analysis takes the scattering at albedo 1 from the same march as the
    // observations instead of rendering a white copy of the volume: the two agree, and the other
    // layers do not change when it is asked for.
    Volume v = makeBuiltinScene("plume", 20);
    auto& albedo = v.ensureAlbedo();
    for (size_t i = 0; i < albedo.size(); ++i) albedo[i] = 0.2f + 0.6f * float((i * 7) % 10) / 10.0f;  // tinted, varying
    GpuVolume gpu(v);
    Volume white = v;
    white.ensureAlbedo().assign(white.storedVoxels() * 3, 1.0f);
    GpuVolume whiteGpu(white);
    const Lighting l = sky({0.4, 0.6, 0.9});
    const RenderLayers plain = test::sharedRenderer().renderLayers(gpu, smallCamera(), l);
    const RenderLayers both = test::sharedRenderer().renderLayers(gpu, smallCamera(), l, {}, nullptr, WorkBudget(), true);
    const RenderLayers whiteLayers = test::sharedRenderer().renderLayers(whiteGpu, smallCamera(), l);
    EXPECT_TRUE(plain.scatteringAtAlbedoOne.empty());
    ASSERT_EQ(both.scatteringAtAlbedoOne.width, 24);
    EXPECT_EQ(maxDifference(both.beauty, plain.beauty, true), 0.0);
    EXPECT_EQ(maxDifference(both.scattering, plain.scattering, true), 0.0);
    double peak = 0;
    for (float x : whiteLayers.scattering.rgba) peak = std::max(peak, double(x));
    const double d = maxDifference(both.scatteringAtAlbedoOne, whiteLayers.scattering, false);
    std::printf("[ measured ] albedo-1 layer vs a white volume's scattering: %.2e of the peak %.3f\n", d / peak, peak);
    EXPECT_GT(peak, 0.05);
    // The two marches stop early at different depths (each by its own radiance): within 1e-3.
    EXPECT_LE(d, 1e-3 * peak);
}

TEST(RenderLayers, TheExrHoldsTheLayersUnderNukesNames) {
    VOLSTYLE_REQUIRE_GL();
    Volume v = makeBuiltinScene("plume", 16);
    GpuVolume gpu(v);
    const RenderLayers layers = test::sharedRenderer().renderLayers(gpu, smallCamera(), sky({0.4, 0.6, 0.9}));
    const auto path = test::scratchDir() / "layers.exr";
    saveExrLayers(path.string(), exrLayersOf(layers), /*halfFloat=*/false);
    // The main RGBA reads back as the medium; the channel list names every layer.
    const Image back = loadImage(path.string()).image;
    EXPECT_LE(maxDifference(back, layers.medium, true), 1e-6);
    const std::string bytes = test::readBytes(path);
    for (const char* channel : {"background.R", "emission.G", "scattering.B", "transmittance.R"})
        EXPECT_NE(bytes.find(std::string(channel) + '\0'), std::string::npos) << channel;
}

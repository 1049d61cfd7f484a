// The translucent preview (core/translucent/, issue #14): half-angle slicing converges to the
// single-scattering renderer as the slices get closer (indirect light off, isotropic phase); a
// thick block lit from behind, black in single scattering, glows in the transport colour with the
// indirect light, more with a wider blur and less with more indirect extinction.
#include <gtest/gtest.h>

#include <cmath>

#include "../common/closed_form.h"
#include "../common/stamped_cloud.h"
#include "core/base/errors.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/volume/builtin_scenes.h"
#include "core/render/gpu_volume.h"
#include "core/translucent/translucent_renderer.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

TranslucentRenderer& translucent() {
    static TranslucentRenderer r(test::device());
    return r;
}

double relativeRms(const Image& a, const Image& b) {
    double num = 0, den = 0;
    for (size_t i = 0; i < a.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            num += std::pow(double(a.rgba[4 * i + c]) - b.rgba[4 * i + c], 2);
            den += std::pow(double(b.rgba[4 * i + c]), 2);
        }
    return std::sqrt(num / den);
}

/// Mean RGB over the pixels where the medium covers the image (alpha > 0.5 in `mask`).
Vec3d meanOver(const Image& img, const Image& mask) {
    Vec3d sum;
    int n = 0;
    for (size_t i = 0; i < img.pixelCount(); ++i)
        if (mask.rgba[4 * i + 3] > 0.5f) sum += Vec3d(img.rgba[4 * i], img.rgba[4 * i + 1], img.rgba[4 * i + 2]), ++n;
    return n ? sum / double(n) : Vec3d();
}

/// The cube [-1,1]³ at n³ holding a smooth blob, σ = peak · exp(-(x² + yScale·y² + z²) / width).
Volume gaussianBlob(int n, double peak, double yScale, double width) {
    Volume blob = test::constantCube(n, 0.0f);
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double h = 0.5 * n, x = (i + 0.5 - h) / h, y = (j + 0.5 - h) / h, z = (k + 0.5 - h) / h;
                const float sigma = float(peak * std::exp(-(x * x + yScale * y * y + z * z) / width));
                for (int c = 0; c < 3; ++c) blob.extinction()[3 * blob.index(i, j, k) + size_t(c)] = sigma;
            }
    return blob;
}

/// Mean red over the covered pixels within `band` pixels of an uncovered one: where the blur
/// brings in the light that passed beside the block.
double rimMean(const Image& img, const Image& mask, int band) {
    auto covered = [&](int x, int y) { return x >= 0 && y >= 0 && x < mask.width && y < mask.height && mask.pixel(x, y)[3] > 0.5f; };
    double sum = 0;
    int n = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            if (!covered(x, y)) continue;
            bool rim = false;
            for (int dy = -band; dy <= band && !rim; ++dy)
                for (int dx = -band; dx <= band && !rim; ++dx) rim = !covered(x + dx, y + dy);
            if (rim) sum += img.pixel(x, y)[0], ++n;
        }
    return n ? sum / n : 0;
}

}  // namespace

TEST(Translucent, ConvergesToSingleScatteringAsTheSlicesGetCloser) {
    VOLSTYLE_REQUIRE_GL();
    Volume cloud = test::thinCloud(24);
    for (float& a : cloud.ensureAlbedo()) a = 0.8f;
    GpuVolume gpu(cloud);
    Lighting l;
    l.lights = {{{0.5, 0.7, 0.4}, {3, 3, 3}}};
    l.background.color = {0.1, 0.15, 0.2};
    l.phase = {PhaseType::Isotropic, 0};
    Camera cam;
    cam.eye = {0.4, 0.5, 3.0};
    cam.target = {0, 0, 0};
    cam.fovYDeg = 36;
    cam.width = cam.height = 48;
    RenderSettings exact;
    exact.terminationThreshold = 0;
    exact.stepVoxels = 0.25;
    const Image reference = test::sharedRenderer().render(gpu, cam, l, exact);
    TranslucentSettings s;
    s.indirect.enabled = false;
    double previous = 1e9, finest = 0;
    for (double spacing : {2.0, 1.0, 0.5, 0.25}) {
        s.sliceSpacing = spacing;
        TranslucentStats stats;
        const Image img = translucent().render(gpu, cam, l, s, &stats);
        finest = relativeRms(img, reference);
        std::printf("[ measured ] translucent vs single scattering, spacing %.2f voxels (%d slices, %.0f ms): relative RMS %.4f\n",
                    spacing, stats.slices, stats.totalMs, finest);
        EXPECT_LT(finest, previous * 1.05) << "spacing " << spacing;
        previous = finest;
    }
    EXPECT_LE(finest, 0.02);
}

// The built-in cloud at 24³ is dense (up to 3.3 optical depths per voxel): there the ray marcher's
// light-depth grid (depth trilinear between nodes) is visibly off, and the slices, which accumulate
// the light's attenuation at the light buffer's resolution, follow the exact light integral (the
// float64 oracle marching from every sample to the light).
TEST(Translucent, FollowsTheExactLightIntegralInADenseCloud) {
    VOLSTYLE_REQUIRE_GL();
    const Volume cloud = makeBuiltinScene("cloud", 24);
    GpuVolume gpu(cloud);
    Lighting l;
    l.lights = {{{0.25, 0.3, -1.0}, {30, 28, 25}}};  // from behind: the rims are lit through depth
    l.background.color = {0, 0, 0};
    l.phase = {PhaseType::Isotropic, 0};
    Camera cam;
    cam.eye = {0, 0.15, 3.2};
    cam.target = {0, -0.05, 0};
    cam.fovYDeg = 36;
    cam.width = cam.height = 40;
    const Image exact = cpu_ref::renderReference<double>(cloud, cam, l, 0.25, cpu_ref::LightDepthMethod::Exact);
    RenderSettings fine;
    fine.stepVoxels = 0.25;
    fine.terminationThreshold = 0;
    const Image marched = test::sharedRenderer().render(gpu, cam, l, fine);
    TranslucentSettings s;
    s.indirect.enabled = false;
    s.sliceSpacing = 0.25;
    const Image sliced = translucent().render(gpu, cam, l, s);
    const double slicedError = relativeRms(sliced, exact), marchedError = relativeRms(marched, exact);
    std::printf("[ measured ] dense cloud lit from behind, against the exact light integral: slices %.4f, ray marcher %.4f\n",
                slicedError, marchedError);
    EXPECT_LE(slicedError, 0.02);
}

TEST(Translucent, ABlockLitFromBehindGlowsInTheTransportColour) {
    VOLSTYLE_REQUIRE_GL();
    Volume block = test::constantCube(16, 4.0f);  // [-1,1]³: optical depth 8 through it
    GpuVolume gpu(block);
    Lighting l;
    l.lights = {{{0, 0, -1}, {10, 10, 10}}};  // behind the block, shining toward the camera
    l.background.color = {0, 0, 0};
    Camera cam;
    cam.eye = {0, 0, 6};  // the block covers the middle three quarters of the frame
    cam.target = {0, 0, 0};
    cam.fovYDeg = 30;
    cam.width = cam.height = 32;
    RenderSettings exact;
    exact.terminationThreshold = 0;
    const Image single = test::sharedRenderer().render(gpu, cam, l, exact);
    TranslucentSettings s;
    s.sliceSpacing = 1.0;
    s.lightBufferSize = 128;
    s.indirect.extinction = 0.2;
    s.indirect.blurAngleDeg = 30;
    s.indirect.transportColor = {1.0, 0.7, 0.4};
    const Image glow = translucent().render(gpu, cam, l, s);
    const Vec3d dark = meanOver(single, single), lit = meanOver(glow, single);
    std::printf("[ measured ] block lit from behind: single scattering %.2e, translucent (%.3f, %.3f, %.3f)\n", dark.x, lit.x, lit.y, lit.z);
    EXPECT_LT(dark.x, 0.01);  // light only through the block's edges
    EXPECT_GT(lit.x, 20 * std::max(dark.x, 1e-6));
    EXPECT_GT(lit.x, lit.y);  // turned toward the transport colour
    EXPECT_GT(lit.y, lit.z);
    // More blur gathers more of the light that passed beside the block (near its rim: a uniform
    // medium blurs light into itself); more indirect extinction lets less through.
    double last = 0;
    for (double angle : {0.0, 30.0, 60.0}) {
        s.indirect.blurAngleDeg = angle;
        const Image img = translucent().render(gpu, cam, l, s);
        const double g = rimMean(img, single, 3);
        std::printf("[ measured ] blur %.0f°: glow at the rim %.4f, overall %.4f\n", angle, g, meanOver(img, single).x);
        EXPECT_GT(g, last * 1.05) << "blur " << angle;
        last = g;
    }
    s.indirect.blurAngleDeg = 30;
    last = 1e9;
    for (double k : {0.1, 0.2, 0.4}) {
        s.indirect.extinction = k;
        const double g = meanOver(translucent().render(gpu, cam, l, s), single).x;
        std::printf("[ measured ] indirect extinction %.1f: glow %.4f\n", k, g);
        EXPECT_LT(g, last) << "extinction " << k;
        last = g;
    }
}

TEST(Translucent, BadSettingsNameTheirField) {
    TranslucentSettings s;
    s.sliceSpacing = -1;
    s.indirect.blurAngleDeg = std::nan("");
    s.indirect.transportColor = {1.5, 0.5, 0.5};
    s.surfaceShading = 2;
    std::vector<std::string> fields;
    for (const auto& p : s.check()) fields.push_back(p.field);
    EXPECT_EQ(fields, (std::vector<std::string>{"slice_spacing", "indirect/blur_angle_deg", "indirect/transport_color", "surface_shading"}));
    EXPECT_THROW(s.validate(), InvalidArgument);
}

// Volume perturbation (Sec. 3.4): amplitude 0 is the identity exactly, the same seed and time give
// the same frame, a small step in time a small change (no popping), and the render-time field
// matches the same field baked into the volume (perturbVolume) up to resampling.
TEST(Translucent, PerturbationIsExactWhenOffRepeatableAndMatchesItsBakedVolume) {
    VOLSTYLE_REQUIRE_GL();
    const Volume cloud = test::thinCloud(24);
    GpuVolume gpu(cloud);
    Lighting l;
    l.lights = {{{0.5, 0.7, 0.4}, {3, 3, 3}}};
    l.background.color = {0, 0, 0};
    Camera cam;
    cam.eye = {0.4, 0.5, 3.0};
    cam.target = {0, 0, 0};
    cam.fovYDeg = 36;
    cam.width = cam.height = 40;
    TranslucentSettings s;
    s.indirect.enabled = false;
    const Image plain = translucent().render(gpu, cam, l, s);
    s.perturbation.frequency = 6;  // off: amplitudes 0
    const Image off = translucent().render(gpu, cam, l, s);
    EXPECT_EQ(off.rgba, plain.rgba);

    s.perturbation.amplitude = 1.5;
    s.perturbation.propertyAmplitude = 0.3;
    s.perturbation.seed = 7;
    s.perturbation.time = 2.0;
    const Image a = translucent().render(gpu, cam, l, s), b = translucent().render(gpu, cam, l, s);
    EXPECT_EQ(a.rgba, b.rgba);
    const double changed = relativeRms(a, plain);
    s.perturbation.time = 2.02;
    const double step = relativeRms(translucent().render(gpu, cam, l, s), a);
    s.perturbation.time = 2.0;
    s.perturbation.seed = 8;
    const double otherSeed = relativeRms(translucent().render(gpu, cam, l, s), a);
    s.perturbation.seed = 7;
    // Baked: the same field on the host, rendered without perturbation. Baking resamples the grid
    // once more (which blurs voxel-sized detail) and keeps only what the grid can hold, so compare
    // on a smooth blob with one smooth octave.
    const Volume blob = gaussianBlob(24, 4, 2, 0.15);
    GpuVolume blobGpu(blob);
    s.perturbation.octaves = 1;
    s.perturbation.frequency = 3;
    s.perturbation.amplitude = 2.5;
    const Image smooth = translucent().render(blobGpu, cam, l, s);
    GpuVolume bakedGpu(perturbVolume(blob, s.perturbation));
    TranslucentSettings plainSettings = s;
    plainSettings.perturbation = Perturbation{};
    const double smoothChange = relativeRms(smooth, translucent().render(blobGpu, cam, l, plainSettings));
    const double baked = relativeRms(translucent().render(bakedGpu, cam, l, plainSettings), smooth);
    std::printf("[ measured ] perturbation: %.4f from the plain frame, %.4f after a time step of 0.02, %.4f with another seed, "
                "a smooth blob, one octave: %.4f from the plain frame and %.4f from its baked volume\n", changed, step, otherSeed, smoothChange, baked);
    EXPECT_GT(changed, 0.02);            // it does something
    EXPECT_LT(step, 0.1 * changed);      // and moves continuously with time
    EXPECT_GT(otherSeed, 0.5 * changed); // another seed is another noise
    EXPECT_LT(baked, 0.25 * smoothChange);  // the baked volume is the same field (resampled once more)
}

// Surface shading S (Eq. 11): 0 shades by attenuation only; 1 blends in Blinn–Phong from the
// extinction's gradient, which darkens the sides of a blob that face away from the light.
TEST(Translucent, SurfaceShadingDarkensTheSidesFacingAway) {
    VOLSTYLE_REQUIRE_GL();
    const Volume blob = gaussianBlob(20, 20, 1, 0.12);
    GpuVolume gpu(blob);
    Lighting l;
    l.lights = {{{1, 0, 0.3}, {5, 5, 5}}};  // from the right
    l.background.color = {0, 0, 0};
    Camera cam;
    cam.eye = {0, 0, 5};
    cam.target = {0, 0, 0};
    cam.fovYDeg = 30;
    cam.width = cam.height = 32;
    TranslucentSettings s;
    s.indirect.enabled = false;
    const Image flat = translucent().render(gpu, cam, l, s);
    s.surfaceShading = 1;
    const Image shaded = translucent().render(gpu, cam, l, s);
    auto side = [](const Image& img, int x0, int x1) {
        double sum = 0;
        for (int y = 12; y < 20; ++y)
            for (int x = x0; x < x1; ++x) sum += img.pixel(x, y)[0];
        return sum;
    };
    const double litFlat = side(flat, 18, 22), litShaded = side(shaded, 18, 22);
    const double awayFlat = side(flat, 10, 14), awayShaded = side(shaded, 10, 14);
    std::printf("[ measured ] surface shading: lit side %.4f -> %.4f, far side %.4f -> %.4f (S 0 -> 1)\n", litFlat, litShaded, awayFlat,
                awayShaded);
    for (float v : shaded.rgba) ASSERT_TRUE(std::isfinite(v));
    EXPECT_LT(awayShaded / awayFlat, 0.8 * (litShaded / litFlat));  // the far side loses more
}

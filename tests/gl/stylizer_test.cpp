// The light-shaft stylizer against closed forms (issue #11): average visibility under a plane
// with a square hole, and single scattering with nothing in the way.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>

#include "core/stylize/stylizer.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

constexpr double kPlaneY = 1.0, kHalfSide = 4.0;
double kHoleHalf = 0.6;  // the plane's square hole (a test may make it small)

void addQuad(Mesh& m, Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    const auto base = uint32_t(m.positions.size());
    for (const Vec3& p : {a, b, c, d}) m.positions.push_back(p), m.normals.push_back({0, 1, 0});
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
}

/// The plane y = 1 over [-4, 4]² without the square [-0.6, 0.6]², as four quads.
Mesh planeWithHole() {
    Mesh m;
    const float L = float(kHalfSide), h = float(kHoleHalf), y = float(kPlaneY);
    addQuad(m, {-L, y, -L}, {-L, y, L}, {-h, y, L}, {-h, y, -L});
    addQuad(m, {h, y, -L}, {h, y, L}, {L, y, L}, {L, y, -L});
    addQuad(m, {-h, y, -L}, {-h, y, -h}, {h, y, -h}, {h, y, -L});
    addQuad(m, {-h, y, h}, {-h, y, L}, {h, y, L}, {h, y, h});
    return m;
}

/// The part of t ∈ [0, s] where the ray's xz-projection lies inside the square |x|,|z| < half.
double insideSquare(const Vec3d& e, const Vec3d& w, double half, double s) {
    double lo = 0, hi = s;
    for (int a : {0, 2}) {
        if (std::abs(w[a]) < 1e-12) {
            if (std::abs(e[a]) >= half) return 0;
            continue;
        }
        double t0 = (-half - e[a]) / w[a], t1 = (half - e[a]) / w[a];
        lo = std::max(lo, std::min(t0, t1));
        hi = std::min(hi, std::max(t0, t1));
    }
    return std::max(0.0, hi - lo);
}

StylizerScene holeScene() {
    StylizerScene s;
    s.occluders = {{"plane", std::make_shared<const Mesh>(planeWithHole()), Mat4::identity(), {0.5, 0.5, 0.5}, {}}};
    s.light.direction = {0, 1, 0};  // straight down through the hole
    s.light.shadowMapSize = 2048;
    s.medium = {0.1, 0.8, {PhaseType::HenyeyGreenstein, 0.3}};
    s.camera.eye = {0.35, 0.3, 6};
    s.camera.target = {0, 0.7, 0};
    s.camera.fovYDeg = 50;
    s.camera.width = 64;
    s.camera.height = 48;
    s.camera.farDist = 14;
    return s;
}

}  // namespace

/// Max |V̄ − exact| over the pixels whose surface distance matches the exact one, with the
/// closed form's hole of half-side `holeHalf` (0: no shaft).
double worstVisibilityError(const StylizerScene& scene, const StylizedFrame& f, double holeHalf, int* comparedOut, int* silhouetteOut);

TEST(Stylizer, AverageVisibilityUnderAPlaneWithAHoleIsTheShaftsShare) {
    VOLSTYLE_REQUIRE_GL();
    kHoleHalf = 0.6;
    const StylizerScene scene = holeScene();
    Stylizer stylizer(test::device());
    for (VisibilityMethod method : {VisibilityMethod::Naive, VisibilityMethod::Accelerated}) {
        StylizeSettings settings;
        settings.method = method;
        settings.steps = 1024;
        const StylizedFrame f = stylizer.render(scene, settings);
        int compared = 0, silhouette = 0;
        const double worst = worstVisibilityError(scene, f, kHoleHalf, &compared, &silhouette);
        const Camera& cam = scene.camera;
        std::cout << "[ measured ] " << (method == VisibilityMethod::Naive ? "naive V̄ (1024 steps" : "accelerated V̄ (min-max mipmap")
                  << ", 2048² map) vs closed form: max |error| " << worst << " over " << compared << " pixels ("
                  << silhouette << " silhouette pixels skipped)\n";
        EXPECT_LE(worst, 1.0 / 255);
        EXPECT_LE(silhouette, cam.width * cam.height / 50);
    }
}

TEST(Stylizer, ClosingFillsTheHoleForTheScatteringOnly) {
    VOLSTYLE_REQUIRE_GL();
    kHoleHalf = 0.02;  // 10 texels of the 2048² map across
    StylizerScene scene = holeScene();
    StylizeSettings settings;
    settings.steps = 1024;
    Stylizer stylizer(test::device());
    const StylizedFrame open = stylizer.render(scene, settings);
    scene.occluders[0].manipulation = {8, MorphShape::Disc};
    const StylizedFrame closed = stylizer.render(scene, settings);
    int compared = 0, silhouette = 0;
    // Closed: V̄ is that of a plane without a hole; open: with it.
    const double closedError = worstVisibilityError(scene, closed, 0.0, &compared, &silhouette);
    const double openError = worstVisibilityError(scene, open, 0.02, &compared, &silhouette);
    std::cout << "[ measured ] closing (disc, 8 texels) of a 10-texel hole: V̄ vs a plane without it, max |error| "
              << closedError << "; before closing vs with the hole " << openError << "\n";
    EXPECT_LE(closedError, 1.0 / 255);
    EXPECT_LE(openError, 1.0 / 255);
    // The surfaces' map keeps the hole; only the scattering's is closed.
    const int n = scene.light.shadowMapSize;
    EXPECT_EQ(closed.shadowMap.pixel(n / 2, n / 2)[0], 1.0f);
    EXPECT_LT(closed.modifiedShadowMap.pixel(n / 2, n / 2)[0], 1.0f);
    EXPECT_EQ(open.modifiedShadowMap.pixel(n / 2, n / 2)[0], 1.0f);
}

/// A transfer function image: `f(column, row)` RGBA for a w×h image.
template <typename F>
std::shared_ptr<const Image> transferImage(int w, int h, F f) {
    auto img = std::make_shared<Image>(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::array<float, 4> v = f(x, y);
            std::copy(v.begin(), v.end(), img->pixel(x, y));
        }
    return img;
}

TEST(Stylizer, TransferFunctionsMultiplyOrReplaceTheScatteringOnly) {
    VOLSTYLE_REQUIRE_GL();
    kHoleHalf = 0.6;
    StylizerScene scene = holeScene();
    Stylizer stylizer(test::device());
    const StylizedFrame plain = stylizer.render(scene, {});

    // A white `multiply` TF is the physical image, bit for bit.
    scene.transferFunction = TransferFunction{transferImage(16, 8, [](int, int) { return std::array<float, 4>{1, 1, 1, 1}; }),
                                              TransferFunction::Mode::Multiply, 0, 20};
    const StylizedFrame white = stylizer.render(scene, {});
    EXPECT_EQ(white.frame.rgba, plain.frame.rgba);

    // Red where V̄ < 0.5 (columns 0–127 of 256), white elsewhere: the low-visibility pixels lose
    // their green and blue scattering, the rest are untouched (a texel's width from 0.5 blends).
    scene.transferFunction->image = transferImage(256, 4, [](int x, int) {
        return x < 128 ? std::array<float, 4>{1, 0, 0, 1} : std::array<float, 4>{1, 1, 1, 1};
    });
    const StylizedFrame red = stylizer.render(scene, {});
    int low = 0, high = 0;
    for (int y = 0; y < scene.camera.height; ++y)
        for (int x = 0; x < scene.camera.width; ++x) {
            const float vBar = plain.averageVisibility.pixel(x, y)[0];
            const float* a = plain.frame.pixel(x, y);
            const float* b = red.frame.pixel(x, y);
            const float* scat = plain.scattering.pixel(x, y);
            if (vBar < 0.5f - 1.0f / 256) {
                ++low;
                EXPECT_EQ(b[0], a[0]) << x << "," << y;
                EXPECT_NEAR(b[1], a[1] - scat[1], 1e-6f * std::max(1.0f, a[1])) << x << "," << y;
                EXPECT_NEAR(b[2], a[2] - scat[2], 1e-6f * std::max(1.0f, a[2])) << x << "," << y;
            } else if (vBar > 0.5f + 1.0f / 256) {
                ++high;
                for (int c = 0; c < 3; ++c) EXPECT_EQ(b[c], a[c]) << x << "," << y;
            }
        }
    EXPECT_GT(low, 100);
    EXPECT_GT(high, 100);

    // `replace`: F.rgb·F.a is the scattering.
    scene.transferFunction = TransferFunction{transferImage(4, 4, [](int, int) { return std::array<float, 4>{0.2f, 0.3f, 0.4f, 0.5f}; }),
                                              TransferFunction::Mode::Replace, 0, 20};
    const StylizedFrame replaced = stylizer.render(scene, {});
    const float expected[3] = {0.1f, 0.15f, 0.2f};
    for (size_t i = 0; i < plain.frame.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(replaced.frame.rgba[4 * i + c] - plain.frame.rgba[4 * i + c] + plain.scattering.rgba[4 * i + c], expected[c], 1e-5);
    EXPECT_EQ(replaced.scattering.rgba, plain.scattering.rgba) << "the AOV is the scattering before the TF";
}

TEST(Stylizer, ScatteringWithNothingInTheWayIsTheClosedForm) {
    VOLSTYLE_REQUIRE_GL();
    StylizerScene scene = holeScene();
    scene.occluders.clear();
    Stylizer stylizer(test::device());
    const StylizedFrame f = stylizer.render(scene, {});
    const Camera& cam = scene.camera;
    const double sigma = scene.medium.extinction, g = scene.medium.phase.g, s = cam.farDist;
    double worst = 0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const double cosTheta = dot(normalize(scene.light.direction), -cam.rayDirection(x, y));
            const double denom = 1 + g * g + 2 * g * cosTheta;
            const double p = (1 - g * g) / (4 * M_PI * denom * std::sqrt(denom));
            for (int c = 0; c < 3; ++c) {
                const double expected = scene.medium.albedo * p * scene.light.irradiance[c] * -std::expm1(-sigma * s);
                worst = std::max(worst, std::abs(f.scattering.pixel(x, y)[c] - expected) / expected);
            }
            EXPECT_EQ(f.averageVisibility.pixel(x, y)[0], 1.0f);
        }
    std::cout << "[ measured ] L_scat without occluders vs ρ p E (1 − e^{−σt s}): max relative error " << worst << "\n";
    EXPECT_LE(worst, 1e-3);
}

/// The spot above the hole, shining down: the hole scene lit by a cone.
StylizerScene spotScene() {
    kHoleHalf = 0.6;
    StylizerScene scene = holeScene();
    scene.light.type = StylizerLightType::Spot;
    scene.light.position = {0.2, 5, -0.3};
    scene.light.direction = {0, 1, 0};
    scene.light.coneDeg = 70;
    scene.light.irradiance = {40, 38, 35};
    return scene;
}

TEST(Stylizer, SpotScatteringWithNothingInTheWayIsItsIntegral) {
    VOLSTYLE_REQUIRE_GL();
    StylizerScene scene = spotScene();
    scene.occluders.clear();
    Stylizer stylizer(test::device());
    StylizeSettings settings;
    settings.spotSteps = 512;
    const StylizedFrame f = stylizer.render(scene, settings);
    const Camera& cam = scene.camera;
    const StylizerLight& l = scene.light;
    const double sigma = scene.medium.extinction, g = scene.medium.phase.g, s = cam.farDist;
    const double cosOuter = std::cos(l.coneDeg * 0.5 * M_PI / 180), cosInner = std::cos(l.coneDeg * 0.4 * M_PI / 180);
    double worst = 0, peak = 0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const Vec3d w = cam.rayDirection(x, y);
            // ∫₀ˢ σt ρ p e^{−σt t} I cone / d² e^{−σt d} dt by a fine midpoint rule in double.
            double sum = 0;
            const int k = 20000;
            for (int i = 0; i < k; ++i) {
                const double t = (i + 0.5) * s / k;
                const Vec3d toLight = l.position - (cam.eye + w * t);
                const double d = length(toLight);
                const Vec3d dir = toLight / d;
                const double a = std::clamp((dot(dir, normalize(l.direction)) - cosOuter) / (cosInner - cosOuter), 0.0, 1.0);
                const double cone = a * a * (3 - 2 * a);
                const double denom = 1 + g * g + 2 * g * dot(dir, -w);
                const double p = (1 - g * g) / (4 * M_PI * denom * std::sqrt(denom));
                sum += std::exp(-sigma * (t + d)) * p * cone / (d * d);
            }
            const double expected = sigma * scene.medium.albedo * sum * s / k * l.irradiance[1];
            peak = std::max(peak, expected);
            worst = std::max(worst, std::abs(f.scattering.pixel(x, y)[1] - expected));
        }
    std::cout << "[ measured ] spot L_scat without occluders (512 steps) vs a 20000-step integral: max |error| " << worst
              << " (" << worst / peak << " of the brightest pixel)\n";
    EXPECT_GT(peak, 0.05);
    EXPECT_LE(worst, 1e-3 * peak);
}

TEST(Stylizer, SpotAverageVisibilityOfBothMethodsAgrees) {
    VOLSTYLE_REQUIRE_GL();
    const StylizerScene scene = spotScene();
    Stylizer stylizer(test::device());
    StylizeSettings naive;
    naive.method = VisibilityMethod::Naive;
    naive.steps = 4096;
    const StylizedFrame a = stylizer.render(scene, naive);
    const StylizedFrame b = stylizer.render(scene, {});
    double worst = 0, lowest = 1;
    for (size_t i = 0; i < a.averageVisibility.pixelCount(); ++i) {
        worst = std::max(worst, double(std::abs(a.averageVisibility.rgba[4 * i] - b.averageVisibility.rgba[4 * i])));
        lowest = std::min(lowest, double(b.averageVisibility.rgba[4 * i]));
    }
    std::cout << "[ measured ] spot light: accelerated V̄ vs naive (4096 steps): max |difference| " << worst << "\n";
    EXPECT_LT(lowest, 0.5) << "the plane shadows part of the view";
    EXPECT_LE(worst, 1.0 / 255);
}

double worstVisibilityError(const StylizerScene& scene, const StylizedFrame& f, double holeHalf, int* comparedOut, int* silhouetteOut) {
    const Camera& cam = scene.camera;
    double worst = 0;
    int compared = 0, silhouette = 0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const Vec3d w = cam.rayDirection(x, y), e = cam.eye;
            // The first surface: the plane, unless the ray goes through the hole or past its edge.
            double s = cam.farDist;
            if (w.y > 0) {
                const double t = (kPlaneY - e.y) / w.y;
                const Vec3d hit = e + w * t;
                const bool onPlane = std::max(std::abs(hit.x), std::abs(hit.z)) < kHalfSide &&
                                     !(std::abs(hit.x) < holeHalf && std::abs(hit.z) < holeHalf);
                if (onPlane && t < s) s = t;
            }
            if (std::abs(f.linearDepth.pixel(x, y)[0] - s) > 1e-3 * s) {
                ++silhouette;  // a pixel whose centre ray and raster coverage disagree at an edge
                continue;
            }
            // In shadow: below the plane and under it, outside the hole. Lit: the rest.
            const double below = w.y > 0 ? std::min(s, (kPlaneY - e.y) / w.y) : s;
            const double lit = s - insideSquare(e, w, kHalfSide, below) + insideSquare(e, w, holeHalf, below);
            const double err = std::abs(f.averageVisibility.pixel(x, y)[0] - lit / s);
            worst = std::max(worst, err);
            ++compared;
        }
    *comparedOut = compared;
    *silhouetteOut = silhouette;
    return worst;
}


// A frame read back without its AOVs (live previews) is the same frame, bit for bit; the AOVs
// stay empty, and the shadow maps too unless asked for.
TEST(Stylizer, AFrameWithoutItsAovsIsTheSameFrame) {
    VOLSTYLE_REQUIRE_GL();
    StylizerScene scene = holeScene();
    scene.light.shadowMapSize = 512;
    Stylizer stylizer(test::device());
    const StylizedFrame full = stylizer.render(scene, {});
    StylizeSettings lean;
    readBackOnly(lean, StylizerOutput::Frame);
    const StylizedFrame frameOnly = stylizer.render(scene, lean);
    ASSERT_EQ(frameOnly.frame.rgba.size(), full.frame.rgba.size());
    EXPECT_EQ(frameOnly.frame.rgba, full.frame.rgba);
    EXPECT_EQ(frameOnly.averageVisibility.pixelCount(), 0u);
    EXPECT_EQ(frameOnly.linearDepth.pixelCount(), 0u);
    EXPECT_EQ(frameOnly.shadowMap.pixelCount(), 0u);
    EXPECT_GT(full.averageVisibility.pixelCount(), 0u);
    StylizeSettings vBar;
    readBackOnly(vBar, StylizerOutput::AverageVisibility);
    EXPECT_EQ(stylizer.render(scene, vBar).averageVisibility.rgba, full.averageVisibility.rgba);
}

// The lights unknown's T and Tᵀ (core/solve/lights_projector.h, issue #13): the adjoint
// identity, T c against the renderer and the float64 oracle under the same lobe radiances.
#include <gtest/gtest.h>

#include <random>

#include "../common/closed_form.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/render/gpu_volume.h"
#include "core/solve/lights_projector.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

Volume lumpyVolume(int n) {
    Volume v = test::constantCube(n, 1.0f);
    std::mt19937 rng(3);
    for (float& s : v.extinction()) s = 0.2f + 3.0f * float(rng() % 1000) / 1000.0f;
    auto& a = v.ensureAlbedo();
    for (float& x : a) x = 0.3f + 0.7f * float(rng() % 1000) / 1000.0f;
    return v;
}

Lighting lobeLighting(int lobes) {
    Lighting l;
    l.lights.clear();
    l.background.color = {0, 0, 0};
    l.phase = {PhaseType::HenyeyGreenstein, 0.3};
    l.environment.lobes = lobes;
    l.environment.lightVolumeResolution = 8;
    return l;
}

std::vector<Camera> twoViews() {
    Camera a = test::axisCamera(12);
    a.fovYDeg = 34;
    Camera b = a;
    b.eye = {4.5, 2.0, 3.0};
    b.width = 10, b.height = 14;
    return {a, b};
}

std::vector<Vec3d> randomRadiance(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::vector<Vec3d> c;
    for (int i = 0; i < n; ++i) c.push_back({double(rng() % 1000) / 500, double(rng() % 1000) / 500, double(rng() % 1000) / 500});
    return c;
}

}  // namespace

namespace {

/// ⟨T c, r⟩ = ⟨c, Tᵀ r⟩ per channel, to 1e-4 of the terms' magnitude.
void expectAdjointIdentity(const Lighting& lighting, bool glass = false) {
    Volume host = lumpyVolume(10);
    if (glass) addGlassSphere(host, {1.4, 0.5, 1.5, 0.05, 3, 1});
    GpuVolume volume(host);
    ASSERT_EQ(bool(volume.refraction()), glass);
    LightsProjector T(test::device(), volume, lighting, 0.5);
    for (const Camera& c : twoViews()) T.addView(c);
    const std::vector<Vec3d> c = randomRadiance(T.lobes(), 1);
    GpuVector tc(T.pixelCount(), "tc"), r(T.pixelCount(), "r");
    T.forward(c, tc);
    std::mt19937 rng(7);
    std::vector<float> rHost(4 * T.pixelCount());
    for (size_t i = 0; i < rHost.size(); ++i) rHost[i] = (i % 4 == 3 || rng() % 5 == 0) ? 0.0f : float(rng() % 2000) / 1000.0f - 1.0f;
    r.upload(rHost);
    const std::vector<Vec3d> tr = T.adjoint(r);
    const std::vector<float> tcHost = tc.download();
    for (int ch = 0; ch < 3; ++ch) {
        double lhs = 0, rhs = 0, scale = 0;
        for (size_t i = 0; i < T.pixelCount(); ++i) {
            lhs += double(tcHost[4 * i + ch]) * rHost[4 * i + ch];
            scale += std::abs(double(tcHost[4 * i + ch]) * rHost[4 * i + ch]);
        }
        for (int i = 0; i < T.lobes(); ++i) rhs += c[size_t(i)][ch] * tr[size_t(i)][ch];
        EXPECT_GT(scale, 0.1);
        EXPECT_NEAR(lhs, rhs, 1e-4 * scale) << "channel " << ch;
    }
}

}  // namespace

TEST(LightsProjector, PassesTheAdjointIdentity) {
    VOLSTYLE_REQUIRE_GL();
    expectAdjointIdentity(lobeLighting(20));  // 20 lobes: two adjoint chunks (kLobeChunk = 16), one partly filled
}

TEST(LightsProjector, PassesTheAdjointIdentityOnRefractedRays) {
    VOLSTYLE_REQUIRE_GL();
    expectAdjointIdentity(lobeLighting(20), true);  // issue #16: T and Tᵀ walk the same bent paths
    Lighting sky = lobeLighting(12);
    sky.background.fromLobes = true;  // the lobes seen directly, in the direction each bent ray leaves
    expectAdjointIdentity(sky, true);
}

namespace {

/// T c equals the renderer (1e-5) and the float64 oracle (1e-4; straight rays only) under the
/// same radiances.
void expectForwardIsTheRender(const Lighting& given, bool glass = false) {
    Lighting lighting = given;
    Volume host = lumpyVolume(8);
    if (glass) addGlassSphere(host, {1.4, 0.5, 1.5, 0.05, 3, 1});
    GpuVolume volume(host);
    LightsProjector T(test::device(), volume, lighting, 0.5);
    const Camera cam = twoViews()[1];
    T.addView(cam);
    lighting.environment.radiance = randomRadiance(T.lobes(), 2);
    GpuVector tc(T.pixelCount(), "tc");
    T.forward(lighting.environment.radiance, tc);
    const std::vector<float> got = tc.download();
    RenderSettings exact;
    exact.terminationThreshold = 0;
    const Image render = test::sharedRenderer().render(volume, cam, lighting, exact);
    const Image oracle = cpu_ref::renderReference<double>(host, cam, lighting, 0.5);
    double maxValue = 0, maxRender = 0, maxOracle = 0;
    for (size_t i = 0; i < T.pixelCount(); ++i)
        for (int ch = 0; ch < 3; ++ch) {
            maxValue = std::max(maxValue, double(oracle.rgba[4 * i + ch]));
            maxRender = std::max(maxRender, double(std::abs(got[4 * i + ch] - render.rgba[4 * i + ch])));
            maxOracle = std::max(maxOracle, double(std::abs(got[4 * i + ch] - oracle.rgba[4 * i + ch])));
        }
    EXPECT_GT(maxValue, 0.05);
    EXPECT_LT(maxRender, 1e-5 * maxValue);
    if (!glass) {
        EXPECT_LT(maxOracle, 1e-4 * maxValue);
    }
}

Lighting lobesAsBackground(int lobes, LobeDomain domain) {
    Lighting l = lobeLighting(lobes);
    l.environment.domain = domain;
    l.background.fromLobes = true;
    l.background.color = {0.3, 0.2, 0.1};  // below a hemisphere basis' horizon
    return l;
}

}  // namespace

TEST(LightsProjector, ForwardIsTheRenderUnderThoseRadiancesAndTheOracles) {
    VOLSTYLE_REQUIRE_GL();
    expectForwardIsTheRender(lobeLighting(12));
    expectForwardIsTheRender(lobesAsBackground(12, LobeDomain::Sphere), true);  // bent rays: T c is the bent render
}

// "background": {"environment": "lobes"}: the sky behind the volume is the lobes' too, so each
// ray's transmittance joins its cell's column; below a hemisphere's horizon the colour stays fixed
// (the test's renderer and oracle see it; T, which leaves it out, is compared where it is not).
TEST(LightsProjector, TheLobesAsTheBackgroundJoinTheirColumns) {
    VOLSTYLE_REQUIRE_GL();
    expectAdjointIdentity(lobesAsBackground(20, LobeDomain::Sphere));
    expectAdjointIdentity(lobesAsBackground(20, LobeDomain::UpperHemisphere));
    Lighting sphere = lobesAsBackground(12, LobeDomain::Sphere);
    sphere.background.color = {0, 0, 0};
    expectForwardIsTheRender(sphere);
}

TEST(LightsProjector, NeedsEnvironmentLobes) {
    VOLSTYLE_REQUIRE_GL();
    GpuVolume volume(lumpyVolume(4));
    Lighting l = lobeLighting(4);
    l.environment.lobes = 0;
    EXPECT_THROW(LightsProjector(test::device(), volume, l, 0.5), InvalidArgument);
}

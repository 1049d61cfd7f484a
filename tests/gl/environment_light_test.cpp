// Environment lighting through the lobe basis (SPEC §8, issue #13): the lobes light the volume
// like directional lights through their light volumes. Checked against the closed form of a
// homogeneous slab and against the float64 CPU oracle.
#include <gtest/gtest.h>

#include <cmath>

#include "../common/closed_form.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/render/gpu_volume.h"
#include "core/render/lobe_volumes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// Lobes of an upper-hemisphere basis, lit only within 60° of the zenith (so every light path
/// from the slab's centre leaves through its top), with radiances that differ per lobe.
EnvironmentLight skyLobes(int n) {
    EnvironmentLight env;
    env.lobes = n;
    env.domain = LobeDomain::UpperHemisphere;
    const LobeBasis basis = env.basis();
    for (int i = 0; i < n; ++i) {
        const double y = basis.directions[size_t(i)].y;
        env.radiance.push_back(y > 0.5 ? Vec3d(0.5 + 0.1 * (i % 7), 0.4, 0.3 + 0.05 * (i % 3)) : Vec3d());
    }
    return env;
}

}  // namespace

TEST(EnvironmentLight, ThinSlabMatchesItsClosedFormToOnePerMille) {
    VOLSTYLE_REQUIRE_GL();
    test::SlabScene slab;
    slab.sigma = 1.0;  // thin: optical depth 0.5 across
    Lighting lighting = slab.lighting();
    lighting.lights.clear();
    lighting.environment = skyLobes(32);
    lighting.environment.lightVolumeResolution = 64;  // the slab's own grid
    GpuVolume volume(slab.volume());
    const Camera cam = slab.camera();
    const Image img = test::sharedRenderer().render(volume, cam, lighting);

    const LobeBasis basis = lighting.environment.basis();
    const std::vector<double> omega = basis.solidAngles();
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const Vec3d dir = cam.rayDirection(x, y);
            Vec3d expected;
            for (int i = 0; i < basis.size(); ++i) {
                const Vec3d& w = basis.directions[size_t(i)];
                const Vec3d E = lighting.environment.radiance[size_t(i)] * omega[size_t(i)];
                if (maxComponent(E) <= 0) continue;
                // slab.radiance with the lobe as its sun: ρ p E (1 − e^{−σ s k}) / k, k = 1 + a / cos θ.
                const double a = std::abs(dir.y), s = slab.d / a, k = 1 + a / w.y;
                expected += E * (slab.albedo * slab.phase(dot(w, -dir)) * -std::expm1(-slab.sigma * s * k) / k);
            }
            // Measured: within 2e-5 relative (light volumes on the slab's own grid).
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(img.pixel(x, y)[c], expected[c], 1e-3 * expected[c]) << x << "," << y << " c" << c;
        }
}

TEST(EnvironmentLight, AgreesWithTheFloat64Oracle) {
    VOLSTYLE_REQUIRE_GL();
    Volume volume = test::constantCube(12, 1.5f);
    // A lumpy extinction and an albedo pattern so light volumes differ per lobe.
    for (int k = 0; k < 12; ++k)
        for (int j = 0; j < 12; ++j)
            for (int i = 0; i < 12; ++i) volume.extinction()[volume.index(i, j, k)] = float(0.5 + 2.0 * ((i + 2 * j + 3 * k) % 5) / 4.0);
    for (size_t i = 0; i < volume.voxelCount(); ++i) volume.ensureAlbedo()[3 * i + (i % 3)] = 0.9f;
    Lighting lighting;
    lighting.lights.clear();
    lighting.phase = {PhaseType::HenyeyGreenstein, 0.4};
    lighting.environment.lobes = 16;
    auto map = std::make_shared<Image>(32, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            float* p = map->pixel(x, y);
            p[0] = 1.0f + float(x) / 16, p[1] = 2.0f - float(y) / 8, p[2] = 0.5f, p[3] = 1;
        }
    lighting.environment.map = map;
    lighting.environment.lightVolumeResolution = 8;  // coarser than the volume: resampled
    Camera cam = test::axisCamera(9);
    cam.fovYDeg = 30;
    GpuVolume gpu(volume);
    RenderSettings settings;
    settings.terminationThreshold = 0;
    const Image gl = test::sharedRenderer().render(gpu, cam, lighting, settings);
    const Image ref = cpu_ref::renderReference<double>(volume, cam, lighting, settings.stepVoxels);
    double maxDiff = 0, maxValue = 0;
    for (size_t i = 0; i < gl.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            maxDiff = std::max(maxDiff, double(std::abs(gl.rgba[4 * i + c] - ref.rgba[4 * i + c])));
            maxValue = std::max(maxValue, double(ref.rgba[4 * i + c]));
        }
    EXPECT_GT(maxValue, 0.05);
    EXPECT_LT(maxDiff, 1e-4 * maxValue);  // measured: 2.2e-5 (float32)
}

TEST(EnvironmentLight, LightVolumesAreCachedUntilTheExtinctionChanges) {
    VOLSTYLE_REQUIRE_GL();
    Volume v = test::constantCube(8, 1.0f);
    GpuVolume volume(v);
    RenderStats stats;
    const LobeBasis basis = LobeBasis::make(8, LobeDomain::Sphere);
    auto a = lobeLightVolumes(test::device(), volume, basis, 64, RenderSettings{}, stats);
    EXPECT_EQ(stats.lightVolumesRecomputed, 8);
    auto b = lobeLightVolumes(test::device(), volume, basis, 64, RenderSettings{}, stats);
    EXPECT_EQ(a.get(), b.get());
    EXPECT_EQ(stats.lightVolumesRecomputed, 8);
    EXPECT_EQ(a->dims, (Int3{8, 8, 8}));
    EXPECT_EQ(lobeGridDims({200, 100, 50}, 64), (Int3{64, 32, 16}));
}

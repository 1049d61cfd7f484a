// The float64 CPU oracle against closed forms: it must be right before it can judge the GL path.
#include <gtest/gtest.h>

#include "../common/closed_form.h"
#include "core/cpu_ref/reference_renderer.h"

using namespace volstyle;
using namespace volstyle::core;

TEST(CpuReference, EmissiveCubeAlongAnAxis) {
    // Constant medium: the segment quadrature telescopes to the exact integral (1e-12: float64).
    Volume cube = test::constantCube(8, 1.5f, Vec3(0.8f, 0.5f, 0.2f));
    Camera cam = test::axisCamera();
    Image img = cpu_ref::renderReference<double>(cube, cam, test::darkLighting(), 0.5);
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            Vec3d dir = cam.rayDirection(x, y);
            // Emission is stored as float; 1e-7 relative covers float(0.8) etc.
            EXPECT_NEAR(img.pixel(x, y)[0], test::cubeRadiance(0.8, 0, 1.5, dir), 1e-6);
            EXPECT_NEAR(img.pixel(x, y)[2], test::cubeRadiance(0.2, 0, 1.5, dir), 1e-6);
        }
}

TEST(CpuReference, SlabSingleScatteringWithinTheLightVolumeBound) {
    test::SlabScene slab;
    Camera cam = slab.camera();
    Image img = cpu_ref::renderReference<double>(slab.volume(), cam, slab.lighting(), 0.5);
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            Vec3d dir = cam.rayDirection(x, y);
            EXPECT_NEAR(img.pixel(x, y)[1], slab.radiance(dir), slab.errorBound(dir) + 1e-6 * slab.radiance(dir));
        }
}

TEST(CpuReference, LightDepthIsExactInsideTheSlab) {
    // Away from the faces, optical depth toward the sun is σ · depth / cosθ exactly.
    test::SlabScene slab;
    Volume v = slab.volume();
    auto depth = cpu_ref::lightDepthVolume<double>(v, slab.sunDirection(), 0.5);
    for (int j = 0; j < slab.ny; ++j) {
        double yWorld = (j + 0.5) * slab.hy();
        double expected = slab.sigma * (slab.d - yWorld) / slab.sunDirection().y;
        EXPECT_NEAR(depth[3 * v.index(12, j, 12)], expected, 1e-9 * slab.sigma) << j;
    }
}

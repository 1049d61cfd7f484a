// The float64 CPU oracle against closed forms: it must be right before it can judge the GL path.
#include <gtest/gtest.h>

#include "../common/closed_form.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/volume/builtin_scenes.h"

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
    // Away from the faces, optical depth toward the sun is σ · depth / cosθ exactly: from a voxel
    // centre, and from the light-aligned grid (depth is linear in a slab, so trilinear is exact).
    test::SlabScene slab;
    Volume v = slab.volume();
    auto grid = cpu_ref::lightDepthGrid<double>(v, slab.sunDirection(), 0.5);
    for (int j = 0; j < slab.ny; ++j) {
        double yWorld = (j + 0.5) * slab.hy();
        double expected = slab.sigma * (slab.d - yWorld) / slab.sunDirection().y;
        const Vec3T<double> centre(12, j, 12);
        EXPECT_NEAR(cpu_ref::opticalDepthToLight<double>(v, centre, slab.sunDirection(), 0.5).x, expected, 1e-9 * slab.sigma) << j;
        EXPECT_NEAR(grid.at(centre).x, expected, 1e-9 * slab.sigma) << j;
    }
}

TEST(CpuReference, LightGridCoversTheBoxAndPutsAxisLightsOnVoxelCentres) {
    const Int3 n{10, 7, 5};
    const Mat4 indexFromWorld = unitBoxWorldFromIndex(n).inverseAffine();
    // A light straight up: rows are voxel columns, nodes sit on voxel centres (c grows downward).
    LightGrid up = makeLightGrid(n, indexFromWorld, {0, 1, 0});
    for (int j = 0; j < n.y; ++j) {
        Vec3d g = up.gridFromIndex.applyPoint({3, double(j), 2});
        EXPECT_NEAR(g.x - std::round(g.x), 0, 1e-12);
        EXPECT_NEAR(g.y - std::round(g.y), 0, 1e-12);
        EXPECT_NEAR(g.z - std::round(g.z), 0, 1e-12);
    }
    // Any light: every corner of the voxels' box lies inside the nodes, and the inverse is one.
    for (Vec3d dir : {Vec3d(0.3, 0.8, -0.5), Vec3d(-1, 0.01, 0), Vec3d(0.577, -0.577, 0.577)}) {
        LightGrid g = makeLightGrid(n, indexFromWorld, dir);
        for (int corner = 0; corner < 8; ++corner) {
            Vec3d p((corner & 1) ? n.x - 0.5 : -0.5, (corner & 2) ? n.y - 0.5 : -0.5, (corner & 4) ? n.z - 0.5 : -0.5);
            Vec3d q = g.gridFromIndex.applyPoint(p);
            for (int a = 0; a < 3; ++a) {
                EXPECT_GE(q[a], -1e-9);
                EXPECT_LE(q[a], g.dims[a] - 1 + 1e-9);
            }
            Vec3d back = g.indexFromGrid.applyPoint(q);
            EXPECT_NEAR(length(back - p), 0, 1e-9);
        }
        // z steps away from the light, one spacing per node.
        Vec3d step = g.indexFromGrid.applyVector({0, 0, 1});
        EXPECT_NEAR(length(step), kLightGridSpacing, 1e-12);
        EXPECT_LT(dot(step, indexFromWorld.applyVector(dir)), 0);
    }
}

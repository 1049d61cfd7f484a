// The light-depth grid light_depth.comp builds (core/render/light_grid.h) against the float64
// oracle's (cpu_ref::lightDepthGrid), node for node and channel for channel: the depth extended
// past the box's faces (issue #34, both directions along a row), rows half a voxel apart, empty
// bricks skipped, and lights along an axis, oblique, grazing, from below and the directions of an
// environment's lobes. Tolerance: float32 sums of up to a few hundred segments, 1e-5 relative to
// the largest depth plus 1e-5 absolute.
#include <gtest/gtest.h>
#include <epoxy/gl.h>

#include <random>

#include "core/cpu_ref/reference_renderer.h"
#include "core/render/derived_volumes.h"
#include "core/scene/environment_lobes.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// Random RGB extinction with an empty corner (a brick to skip).
Volume lumpy(Int3 dims, float maxSigma, uint32_t seed) {
    Volume v(dims, unitBoxWorldFromIndex(dims));
    std::mt19937 rng(seed);
    for (float& s : v.extinction()) s = maxSigma * float(rng() % 1000) / 1000.0f;
    for (int k = 0; k < dims.z; ++k)
        for (int j = 0; j < dims.y / 2; ++j)
            for (int i = 0; i < dims.x / 2; ++i)
                for (size_t c = 0; c < 3; ++c) v.extinction()[3 * v.index(i, j, k) + c] = 0;
    return v;
}

void expectSameGrid(const Volume& host, const Vec3d& towardLight, double across) {
    GpuVolume volume(host);
    RenderSettings march;
    RenderStats stats;
    updateOccupancy(test::device(), volume, stats);  // the renderer's order: bricks first, then light depth
    const auto gl = computeLightDepth(test::device(), volume, towardLight, march, stats, WorkBudget(), across);
    const auto ref = cpu_ref::lightDepthGrid<double>(host, towardLight, march.stepVoxels, across);
    ASSERT_EQ(gl->grid.dims, ref.grid.dims);
    const size_t nodes = size_t(ref.grid.dims.volume());
    std::vector<float> got(nodes * 4);
    glGetTextureImage(gl->texture.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(got.size() * sizeof(float)), got.data());
    double peak = 0, worst = 0;
    for (size_t i = 0; i < 3 * nodes; ++i) peak = std::max(peak, std::abs(ref.depth[i]));
    for (size_t i = 0; i < nodes; ++i)
        for (size_t c = 0; c < 3; ++c) worst = std::max(worst, std::abs(double(got[4 * i + c]) - ref.depth[3 * i + c]));
    EXPECT_LE(worst, 1e-5 * peak + 1e-5) << "light " << towardLight << ", rows " << across << " voxel apart";
}

}  // namespace

TEST(LightDepthGrid, IsTheOraclesNodeForNode) {
    VOLSTYLE_REQUIRE_GL();
    const Volume host = lumpy({20, 18, 24}, 3.0f, 5);
    for (const Vec3d& dir : {Vec3d(0, 1, 0), Vec3d(-0.55, 0.65, 0.55), Vec3d(0.95, 0.12, -0.3), Vec3d(0.3, -0.9, 0.1)})
        for (double across : {1.0, 0.5}) expectSameGrid(host, dir, across);
}

TEST(LightDepthGrid, IsTheOraclesForEveryLobeDirection) {
    VOLSTYLE_REQUIRE_GL();
    // Directions almost parallel to a face put the light-side crossing far along a row, and the
    // extension toward the light then runs over long stretches (a reversed-ray bug showed here).
    const Volume host = lumpy({8, 8, 8}, 3.0f, 3);
    EnvironmentLight env;
    env.lobes = 12;
    for (const Vec3d& dir : env.basis().directions) expectSameGrid(host, dir, 1.0);
}

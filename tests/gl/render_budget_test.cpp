// Renders under a WorkBudget (issue #9): chunked dispatches give the same pixels as one dispatch,
// a budget stops the light-depth pass and the march between chunks and names them, a cancel flag
// stops them, and nothing half-made is cached.
#include <gtest/gtest.h>

#include <atomic>

#include "core/base/errors.h"
#include "core/base/work_budget.h"
#include "core/render/chunked_dispatch.h"
#include "core/render/gpu_volume.h"
#include "core/volume/builtin_scenes.h"
#include "../common/image_compare.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A 72³ cloud (373,248 voxels: two light-depth chunks) seen in 640×480 (two march chunks).
struct ChunkedScene {
    Volume v = makeBuiltinScene("cloud", 72);
    Camera cam = [] {
        Camera c;
        c.width = 640;
        c.height = 480;
        return c;
    }();
    Lighting l;
};

}  // namespace

TEST(RenderBudget, ChunkedAndSingleDispatchGiveIdenticalPixels) {
    VOLSTYLE_REQUIRE_GL();
    ChunkedScene scene;
    static_assert(72LL * 72 * 72 > kChunkInvocations && 640LL * 480 > kChunkInvocations);
    GpuVolume single(scene.v), chunked(scene.v);  // separate light volumes (own extinction versions)
    Renderer renderer(test::device());
    RenderStats stats;
    const Image a = renderer.render(single, scene.cam, scene.l);
    const Image b = renderer.render(chunked, scene.cam, scene.l, {}, &stats, WorkBudget(1e6));  // bounded: chunked
    EXPECT_EQ(stats.lightVolumesRecomputed, 1);
    EXPECT_EQ(test::maxAbsDifference(a, b), 0.0);
}

TEST(RenderBudget, TheBudgetStopsThePassesAndNamesThem) {
    VOLSTYLE_REQUIRE_GL();
    ChunkedScene scene;
    GpuVolume gpu(scene.v);
    Renderer renderer(test::device());
    try {
        renderer.render(gpu, scene.cam, scene.l, {}, nullptr, WorkBudget(1e-6));
        FAIL() << "expected OverBudget";
    } catch (const OverBudget& e) {
        EXPECT_NE(std::string(e.what()).find("light-depth pass"), std::string::npos) << e.what();
        // Stopped after its first chunk of rows (whole work groups of 8 rows).
        EXPECT_EQ(std::string(e.what()).find("with 100% done"), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()).find("with 0% done"), std::string::npos) << e.what();
    }
    // Nothing half-made was cached: the next render computes the light volume whole.
    RenderStats stats;
    const Image whole = renderer.render(gpu, scene.cam, scene.l, {}, &stats);
    EXPECT_EQ(stats.lightVolumesRecomputed, 1);
    // With the light volume cached, only the march is left to stop.
    try {
        renderer.render(gpu, scene.cam, scene.l, {}, nullptr, WorkBudget(1e-6));
        FAIL() << "expected OverBudget";
    } catch (const OverBudget& e) {
        EXPECT_NE(std::string(e.what()).find("march"), std::string::npos) << e.what();
    }
    GpuVolume fresh(scene.v);
    EXPECT_EQ(test::maxAbsDifference(renderer.render(fresh, scene.cam, scene.l), whole), 0.0);
}

TEST(RenderBudget, ACancelFlagStopsBetweenChunks) {
    VOLSTYLE_REQUIRE_GL();
    ChunkedScene scene;
    GpuVolume gpu(scene.v);
    Renderer renderer(test::device());
    std::atomic<bool> cancel{true};
    EXPECT_THROW(renderer.render(gpu, scene.cam, scene.l, {}, nullptr, WorkBudget(0, &cancel)), Cancelled);
}

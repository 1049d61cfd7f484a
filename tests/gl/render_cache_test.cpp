// Work a frame does not need is not done: light-depth volumes are recomputed only when the
// extinction or the light changes.
#include <gtest/gtest.h>

#include "core/render/gpu_volume.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

TEST(RenderCache, LightVolumesFollowExtinctionAndSun) {
    VOLSTYLE_REQUIRE_GL();
    Renderer renderer(*test::glContext());
    Volume v = makeBuiltinScene("sphere", 16);
    GpuVolume gpu(v);
    Camera cam;
    cam.width = cam.height = 8;
    Lighting l;
    RenderStats s;

    renderer.render(gpu, cam, l, {}, &s);
    EXPECT_EQ(s.lightVolumesRecomputed, 1);
    EXPECT_GT(s.occupancyMs, 0.0);
    renderer.render(gpu, cam, l, {}, &s);  // same everything: cached
    EXPECT_EQ(s.lightVolumesRecomputed, 0);
    EXPECT_EQ(s.occupancyMs, 0.0);

    cam.eye = {1, 1, 3};  // a new camera needs no new light volume
    renderer.render(gpu, cam, l, {}, &s);
    EXPECT_EQ(s.lightVolumesRecomputed, 0);

    for (float& a : v.ensureAlbedo()) a = 0.5f;  // albedo changes: extinction did not
    gpu.upload(v);
    renderer.render(gpu, cam, l, {}, &s);
    EXPECT_EQ(s.lightVolumesRecomputed, 0);

    l.lights[0].direction = {0, 1, 0};  // the sun moves
    renderer.render(gpu, cam, l, {}, &s);
    EXPECT_EQ(s.lightVolumesRecomputed, 1);

    v.extinction()[100] += 1.0f;  // extinction changes
    gpu.upload(v);
    renderer.render(gpu, cam, l, {}, &s);
    EXPECT_EQ(s.lightVolumesRecomputed, 1);
    EXPECT_GT(s.occupancyMs, 0.0);

    l.lights[0].irradiance = {0, 0, 0};  // a dark sun needs no light volume at all
    renderer.render(gpu, cam, l, {}, &s);
    EXPECT_EQ(s.lightVolumesRecomputed, 0);
}

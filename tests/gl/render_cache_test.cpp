// Work a frame does not need is not done: light-depth volumes are recomputed only when the
// extinction or the light changes.
#include <gtest/gtest.h>

#include "core/base/errors.h"
#include "core/gpu/resource_cache.h"
#include "core/render/gpu_volume.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A 16³ sphere, an 8×8 camera and the default sun: small enough that only the caching shows.
struct SmallScene {
    Renderer renderer{test::device()};
    Volume v = makeBuiltinScene("sphere", 16);
    GpuVolume gpu{v};
    Camera cam = [] {
        Camera c;
        c.width = c.height = 8;
        return c;
    }();
    Lighting l;
    RenderStats s;
};

}  // namespace

TEST(RenderCache, LightVolumesFollowExtinctionAndSun) {
    VOLSTYLE_REQUIRE_GL();
    SmallScene scene;
    auto& [renderer, v, gpu, cam, l, s] = scene;

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

TEST(RenderCache, LightVolumeKeyCoversTheTransformAndDims) {
    // The same extinction values on a moved or rotated grid see the light along another index-space
    // direction: the cached light volume must not be reused (the old key had no transform).
    VOLSTYLE_REQUIRE_GL();
    SmallScene scene;
    auto& [renderer, v, gpu, cam, l, s] = scene;
    renderer.render(gpu, cam, l, {}, &s);
    renderer.render(gpu, cam, l, {}, &s);
    EXPECT_EQ(s.lightVolumesRecomputed, 0);
    const uint64_t version = gpu.extinctionVersion();
    Mat4 m = v.worldFromIndex();
    std::swap(m(0, 0), m(0, 1));  // x and y of the index axes swap: a rotated grid, same values
    std::swap(m(1, 0), m(1, 1));
    v.setWorldFromIndex(m);
    gpu.upload(v);
    EXPECT_EQ(gpu.extinctionVersion(), version) << "same values: the version alone cannot tell";
    renderer.render(gpu, cam, l, {}, &s);
    EXPECT_EQ(s.lightVolumesRecomputed, 1);
}

TEST(RenderCache, EvictionNeverFreesWhatIsHeld) {
    // The cache drops its reference beyond its capacity; a holder keeps the resource alive.
    ResourceCache cache(2);
    auto first = cache.insert<int>("a", std::make_shared<const int>(1));
    cache.insert<int>("b", std::make_shared<const int>(2));
    cache.insert<int>("c", std::make_shared<const int>(3));
    EXPECT_EQ(cache.size(), 2u);
    EXPECT_EQ(cache.find<int>("a"), nullptr) << "the least recently used went";
    EXPECT_EQ(*first, 1) << "but its holder still has it";
    EXPECT_EQ(*cache.find<int>("b"), 2);
    cache.insert<int>("d", std::make_shared<const int>(4));
    EXPECT_NE(cache.find<int>("b"), nullptr) << "b was used more recently than c";
    EXPECT_EQ(cache.find<int>("c"), nullptr);
    EXPECT_THROW(cache.find<float>("b"), InternalError);
}

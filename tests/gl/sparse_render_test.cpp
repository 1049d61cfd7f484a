// Sparse volumes on the GPU (issue #39): a volume stored as bricks in an atlas reads every voxel
// as the dense texture does, so it renders the same image, through every lighting path.
#include <gtest/gtest.h>

#include <cmath>

#include <iostream>

#include "core/render/gpu_volume.h"
#include "core/translucent/translucent_renderer.h"
#include "core/volume/builtin_scenes.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// Largest |difference| over every channel of two images of one size.
double maxDifference(const Image& a, const Image& b) {
    double m = 0;
    for (size_t i = 0; i < a.rgba.size(); ++i) m = std::max(m, double(std::abs(a.rgba[i] - b.rgba[i])));
    return m;
}

double maxValue(const Image& a) {
    double m = 0;
    for (float v : a.rgba) m = std::max(m, double(v));
    return m;
}

/// The built-in cloud with a glowing core and tinted albedo (every grid the renderer reads).
Volume glowingCloud(int n) {
    Volume v = makeBuiltinScene("cloud", n);
    auto& e = v.ensureEmission();
    auto& a = v.ensureAlbedo();
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const size_t idx = v.index(i, j, k);
                const double r = std::hypot(i - n / 2.0, j - n / 2.0, k - n / 2.0) / n;
                if (v.extinction()[3 * idx] == 0) continue;  // empty space stays background: bricks there stay inactive
                if (r < 0.2) e[3 * idx] = 2.0f, e[3 * idx + 1] = 0.8f;
                a[3 * idx + 1] = 0.7f;
            }
    return v;
}

/// The default lighting with its sun high and to the side.
Lighting sunFromAbove() {
    Lighting sun;
    sun.lights[0].direction = {0.3, 0.8, -0.5};
    return sun;
}

}  // namespace

TEST(SparseRender, BricksRenderTheDenseImageUnderSunSkyAndGlow) {
    VOLSTYLE_REQUIRE_GL();
    const Volume dense = glowingCloud(40);
    Camera cam = framingCamera(dense.worldBounds());
    cam.width = cam.height = 48;
    Lighting sun = sunFromAbove();
    Lighting sky = sun;
    sky.environment.lobes = 6;  // environment lobes too (light volumes through the bricks)
    sky.environment.radiance.assign(6, Vec3d(0.2, 0.3, 0.5));
    for (Int3 offset : {Int3{0, 0, 0}, Int3{3, 5, 1}, Int3{7, 7, 7}}) {
        const Volume sparse = dense.toSparse(offset);
        ASSERT_TRUE(sparse.isSparse());
        EXPECT_LT(sparse.bricks()->activeBricks(), size_t(sparse.bricks()->brickDims().volume()));  // the corners are empty
        GpuVolume a(dense), b(sparse);
        EXPECT_TRUE(b.isSparse());
        Renderer renderer(test::device());
        for (const Lighting* l : {&sun, &sky}) {
            const Image ia = renderer.render(a, cam, *l);
            const Image ib = renderer.render(b, cam, *l);
            ASSERT_GT(maxValue(ia), 0.05);
            // The same values at every trilinear corner, and the light grids cover only the active
            // bricks with nodes on the same lattice. Bricks on the dense volume's own lattice give
            // it bit for bit; shifted ones bound the light grid elsewhere, so its rows start at
            // another node and sum in another order (float rounding: measured 2.7e-7).
            const double tolerance = offset == Int3{0, 0, 0} ? 0.0 : 1e-6 * maxValue(ia);
            EXPECT_LE(maxDifference(ia, ib), tolerance) << "offset " << offset;
        }
    }
}

TEST(SparseRender, TileBricksSharingOneSlotRenderAsTheirVoxels) {
    VOLSTYLE_REQUIRE_GL();
    // A cloud with a constant cube inside (a tile in a VDB): the cube's 8 bricks share one slot.
    Volume dense = glowingCloud(48);
    for (int k = 16; k < 32; ++k)
        for (int j = 16; j < 32; ++j)
            for (int i = 16; i < 32; ++i) {
                const size_t n = 3 * dense.index(i, j, k);
                for (int c = 0; c < 3; ++c) dense.extinction()[n + size_t(c)] = 5.0f, dense.emission()[n + size_t(c)] = 0.0f;
                dense.albedo()[n] = dense.albedo()[n + 2] = 1.0f, dense.albedo()[n + 1] = 0.7f;
            }
    const BrickLayout own = *dense.toSparse().bricks();
    BrickLayout shared(dense.dims(), {0, 0, 0});
    uint32_t tile = 0;
    own.forEachActiveBrick([&](Int3 b, uint32_t) {
        const bool inCube = b.x >= 2 && b.x < 4 && b.y >= 2 && b.y < 4 && b.z >= 2 && b.z < 4;
        if (!inCube) return void(shared.activate(b));
        if (tile == 0) tile = shared.addSharedSlot(b);
        shared.share(b, tile);
    });
    Volume sparse(shared, dense.worldFromIndex());
    sparse.ensureAlbedo(), sparse.ensureEmission();
    forEachActiveVoxel(sparse, [&](Int3 p, size_t s) {
        const size_t n = 3 * dense.index(p.x, p.y, p.z);
        for (int c = 0; c < 3; ++c) {
            sparse.extinction()[3 * s + size_t(c)] = dense.extinction()[n + size_t(c)];
            sparse.albedo()[3 * s + size_t(c)] = dense.albedo()[n + size_t(c)];
            sparse.emission()[3 * s + size_t(c)] = dense.emission()[n + size_t(c)];
        }
    });
    EXPECT_EQ(sparse.bricks()->slots(), own.slots() - 7);  // 8 bricks in one slot
    EXPECT_EQ(sparse.toDense().extinction(), dense.extinction());
    Camera cam = framingCamera(dense.worldBounds());
    cam.width = cam.height = 40;
    const Lighting sun = sunFromAbove();
    GpuVolume a(dense), b(sparse);
    Renderer renderer(test::device());
    const Image ia = renderer.render(a, cam, sun), ib = renderer.render(b, cam, sun);
    ASSERT_GT(maxValue(ia), 0.05);
    // The same voxel values; the light grid covers the active bricks only (float rounding of its rows).
    EXPECT_LE(maxDifference(ia, ib), 1e-6 * maxValue(ia));
}

TEST(SparseRender, TheTranslucentPreviewReadsBricksAsTheDenseTextures) {
    VOLSTYLE_REQUIRE_GL();
    const Volume dense = glowingCloud(32);
    const Volume sparse = dense.toSparse({5, 0, 3});
    Camera cam = framingCamera(dense.worldBounds());
    cam.width = cam.height = 48;
    const Lighting sun = sunFromAbove();
    GpuVolume a(dense), b(sparse);
    TranslucentRenderer preview(test::device());
    const Image ia = preview.render(a, cam, sun, {}), ib = preview.render(b, cam, sun, {});
    ASSERT_GT(maxValue(ia), 0.05);
    // The texture unit's trilinear filter against 8 fetches through the brick table: equal to
    // the filter's rounding (llvmpipe filters in float; GPUs quantise the weights, 1/256).
    const double d = maxDifference(ia, ib);
    std::cout << "[ measured ] translucent preview, sparse against dense: largest difference " << d / maxValue(ia) << " of the peak\n";
    EXPECT_LE(d, 1e-4 * maxValue(ia));
}

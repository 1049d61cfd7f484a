// Sparse volumes on the GPU (issue #39): a volume stored as bricks in an atlas reads every voxel
// as the dense texture does, so it renders the same image, through every lighting path.
#include <gtest/gtest.h>

#include <cmath>

#include "core/render/gpu_volume.h"
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

}  // namespace

TEST(SparseRender, BricksRenderTheDenseImageUnderSunSkyAndGlow) {
    VOLSTYLE_REQUIRE_GL();
    const Volume dense = glowingCloud(40);
    Camera cam = framingCamera(dense.worldBounds());
    cam.width = cam.height = 48;
    Lighting sun;
    sun.lights[0].direction = {0.3, 0.8, -0.5};
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

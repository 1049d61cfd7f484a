#include <gtest/gtest.h>

#include "core/base/errors.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

std::string problemOf(const Camera& c) {
    auto p = c.check();
    return p.empty() ? "" : p[0].field;
}

}  // namespace

TEST(Camera, DegenerateCamerasAreRejected) {
    Camera ok;
    EXPECT_TRUE(ok.check().empty());
    Camera c = ok;
    c.target = c.eye;
    EXPECT_EQ(problemOf(c), "target");
    c = ok;
    c.up = c.target - c.eye;  // up ∥ view
    EXPECT_EQ(problemOf(c), "up");
    for (double fov : {0.0, 180.0, -5.0}) {
        c = ok;
        c.fovYDeg = fov;
        EXPECT_EQ(problemOf(c), "fov_y_deg") << fov;
    }
    c = ok;
    c.width = 0;
    EXPECT_EQ(problemOf(c), "width");
    c = ok;
    c.height = 8193;
    EXPECT_EQ(problemOf(c), "height");
    c = ok;
    c.nearDist = 5, c.farDist = 4;
    EXPECT_EQ(problemOf(c), "far");
    EXPECT_THROW(c.validate(), InvalidArgument);
}

TEST(Camera, RaysPassThroughPixelCentres) {
    Camera c;
    c.eye = {0, 0, 5};
    c.target = {0, 0, 0};
    c.width = 3, c.height = 3;
    c.fovYDeg = 90;
    Vec3d centre = c.rayDirection(1, 1);
    EXPECT_NEAR(centre.z, -1.0, 1e-15);
    // Top-left pixel centre: (-2/3, +2/3) on the image plane at distance 1 (tan 45° = 1).
    Vec3d tl = c.rayDirection(0, 0);
    EXPECT_NEAR(tl.x / -tl.z, -2.0 / 3, 1e-12);
    EXPECT_NEAR(tl.y / -tl.z, 2.0 / 3, 1e-12);
}

TEST(Camera, TheDefaultCameraFramesAnyBoxFromAHundredthToTenThousandUnits) {
    // Issue #37: `volstyle render` and `volstyle animate` without --camera use framingCamera (the
    // page frames the same way): an artist's VDB, of any size and anywhere, is in view with
    // margin — every corner of its box projects inside the image, and the box's projected
    // extent covers 10–80% of the viewport.
    for (double size : {0.01, 0.05, 2.0, 20.0, 1e4})
        for (Vec3d centre : {Vec3d{0, 0, 0}, Vec3d{20, 10, 5}, Vec3d{0.28, 0.08, -0.23}, Vec3d{-3e4, 5e3, 1e4}}) {
            const Vec3d half = Vec3d{1.0, 0.6, 0.8} * (size / 2);
            const Camera c = framingCamera({centre - half, centre + half});
            EXPECT_TRUE(c.check().empty()) << size;
            int x0 = c.width, y0 = c.height, x1 = -1, y1 = -1;
            for (int k = 0; k < 8; ++k) {
                const Vec3d corner = centre + Vec3d{k & 1 ? half.x : -half.x, k & 2 ? half.y : -half.y, k & 4 ? half.z : -half.z};
                const auto p = c.project(corner);
                ASSERT_TRUE(p) << "a corner of the " << size << "-unit box at " << centre.x << " is out of view";
                x0 = std::min(x0, p->x), x1 = std::max(x1, p->x), y0 = std::min(y0, p->y), y1 = std::max(y1, p->y);
            }
            const double share = double(x1 - x0 + 1) * (y1 - y0 + 1) / (double(c.width) * c.height);
            EXPECT_GE(share, 0.10) << size;
            EXPECT_LE(share, 0.80) << size;
        }
}

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

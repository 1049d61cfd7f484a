// A live frame's read-back (issue #40): the display bytes the GPU packs into a read-back slot are
// the frame's floats through the exact sRGB curve (a float64 reference here; against the PNG's
// bytes and through the JPEG codec: tests/http's MJPEG stream test), and a slot is readable from
// another thread once complete() returns, held until released. No file libraries: this runs in
// gl_tests_device on a GPU too, where persistent coherent mappings are the driver's own.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <thread>

#include "core/base/errors.h"
#include "core/gl/readback_ring.h"
#include "core/stylize/stylizer.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

StylizerScene smallForest() {
    StylizerScene scene = builtinForest();
    scene.camera.width = 160;
    scene.camera.height = 90;
    scene.light.shadowMapSize = 512;
    return scene;
}

TEST(LiveReadback, DisplayBytesAreThePngBytesOfTheSameFrame) {
    VOLSTYLE_REQUIRE_GL();
    const StylizerScene scene = smallForest();
    Stylizer stylizer(test::device());
    StylizeSettings lean;
    readBackOnly(lean, StylizerOutput::Frame);
    const StylizedFrame reference = stylizer.render(scene, lean);
    gl::ReadbackRing ring(2);
    for (double exposure : {0.0, 1.5}) {
        const DisplayReadback display{&ring, exposure};
        const StylizedFrame live = stylizer.render(scene, lean, nullptr, &display);
        ASSERT_NE(live.displayBytes, nullptr);
        EXPECT_TRUE(live.frame.empty());  // the frame is in the slot, not read back as floats
        EXPECT_EQ(ring.held(), 1);
        // Against the exact curve in float64 the GPU's bytes differ only where float rounding
        // tips a half level.
        int largest = 0;
        size_t differing = 0;
        for (size_t i = 0; i < reference.frame.pixelCount(); ++i) {
            for (size_t c = 0; c < 3; ++c) {
                const double v = std::clamp(double(reference.frame.rgba[4 * i + c]) * std::exp2(exposure), 0.0, 1.0);
                const double srgb = v <= 0.0031308 ? v * 12.92 : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
                const int exact = int(std::lround(255 * srgb)), got = live.displayBytes[4 * i + c];
                largest = std::max(largest, std::abs(got - exact));
                differing += got != exact;
            }
            ASSERT_EQ(live.displayBytes[4 * i + 3], 255) << "pixel " << i;
        }
        EXPECT_LE(largest, 1) << "exposure " << exposure;
        EXPECT_LT(double(differing), 1e-3 * 3 * double(reference.frame.pixelCount())) << "exposure " << exposure;
        ring.release(live.displaySlot);
        EXPECT_EQ(ring.held(), 0);
    }
}

TEST(ReadbackRing, ASlotIsReadOnAnotherThreadAndHeldUntilReleased) {
    VOLSTYLE_REQUIRE_GL();
    gl::ReadbackRing ring(2);
    const int a = ring.acquire(4096), b = ring.acquire(1 << 20);
    EXPECT_NE(a, b);
    EXPECT_THROW(ring.acquire(16), GpuError);  // both held
    const uint32_t pattern = 0xA5C3F00Du;
    glClearNamedBufferData(ring.buffer(b).id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &pattern);
    const uint8_t* bytes = ring.complete(b);
    size_t wrong = 0;
    std::thread reader([&] {
        for (size_t i = 0; i < (size_t(1) << 20) / 4; ++i) wrong += reinterpret_cast<const uint32_t*>(bytes)[i] != pattern;
    });
    reader.join();
    EXPECT_EQ(wrong, 0u);
    ring.release(b);  // any thread may; this one here
    EXPECT_EQ(ring.acquire(64), b);  // the free slot again, large enough already
    ring.release(a);
    ring.release(b);
    EXPECT_EQ(ring.held(), 0);
}

}  // namespace

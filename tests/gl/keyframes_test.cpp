// Key-framed TFs along a camera path (issue #15): at a key the frame's TF is that key's exactly,
// midway the two keys' average, and a sequence's frames change no more from one to the next than
// the keys' difference allows; the path's camera at a key is the key's.
#include <gtest/gtest.h>

#include <cmath>

#include "core/stylize/keyframes.h"
#include "core/stylize/stylizer.h"
#include "../common/image_compare.h"
#include "../common/small_forest.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A replace TF of one solid colour (so the scattering is the colour, wherever V̄ and d are).
TransferFunction solidTf(Vec3d colour) {
    TransferFunction tf;
    tf.mode = TransferFunction::Mode::Replace;
    tf.width = 8, tf.height = 8;
    TfLayer layer;
    layer.solid.colour = colour;
    tf.layers = {layer};
    return tf;
}

}  // namespace

TEST(Keyframes, TheTfIsTheKeysAtKeysAndTheirAverageMidway) {
    StylizerScene scene = test::smallForest();
    const Vec3d c0{0.2, 0.4, 0.6}, c1{0.8, 0.2, 0.0};
    StylizerKeyframe k0{0, scene.camera, solidTf(c0)}, k1{2, scene.camera, solidTf(c1)};
    k1.camera.eye = k1.camera.eye + Vec3d(1.0, 0.3, -0.5);
    scene.keyframes = {k0, k1};
    Stylizer stylizer(test::device());
    auto tfAt = [&](double t) { return *stylizer.render(sceneAtTime(scene, t)).transferFunction->image; };
    const Image key0 = compileTfLayers(k0.transferFunction->layers, 8, 8), key1 = compileTfLayers(k1.transferFunction->layers, 8, 8);
    EXPECT_EQ(tfAt(0).rgba, key0.rgba);
    EXPECT_EQ(tfAt(2).rgba, key1.rgba);
    EXPECT_EQ(tfAt(-1).rgba, key0.rgba) << "before the first key: the first key";
    const Image mid = tfAt(1);
    for (size_t i = 0; i < mid.rgba.size(); ++i) EXPECT_NEAR(mid.rgba[i], 0.5 * (key0.rgba[i] + key1.rgba[i]), 1e-6);

    // The path's camera: the key's at a key, halfway between midway.
    EXPECT_EQ(sceneAtTime(scene, 0).camera.eye, k0.camera.eye);
    EXPECT_EQ(sceneAtTime(scene, 2).camera.eye, k1.camera.eye);
    const Vec3d half = (k0.camera.eye + k1.camera.eye) * 0.5;
    EXPECT_LT(length(sceneAtTime(scene, 1).camera.eye - half), 1e-12);
    // A frame at a key is the frame of the key's own scene.
    StylizerScene atKey = test::smallForest();
    atKey.camera = k1.camera;
    atKey.transferFunction = k1.transferFunction;
    EXPECT_EQ(stylizer.render(sceneAtTime(scene, 2)).frame.rgba, stylizer.render(atKey).frame.rgba);
}

TEST(Keyframes, ASequenceChangesNoFasterThanItsKeys) {
    // One camera, two TFs: between frames 1/fps apart each pixel may move by at most the keys'
    // difference times the step's share of the span.
    StylizerScene scene = test::smallForest();
    const Vec3d c0{0.1, 0.5, 0.9}, c1{0.9, 0.3, 0.1};
    scene.keyframes = {{0, scene.camera, solidTf(c0)}, {1, scene.camera, solidTf(c1)}};
    Stylizer stylizer(test::device());
    const std::vector<double> times = sequenceTimes(0, 1, 8, 100);
    ASSERT_EQ(times.size(), 9u);
    EXPECT_DOUBLE_EQ(times.back(), 1.0);
    const double allowed = 0.8 / 8;  // the largest channel difference of the keys, over 8 steps
    double worst = 0;
    Image previous = stylizer.render(sceneAtTime(scene, times[0])).frame;
    for (size_t i = 1; i < times.size(); ++i) {
        Image next = stylizer.render(sceneAtTime(scene, times[i])).frame;
        worst = std::max(worst, test::maxAbsDifference(previous, next));
        previous = std::move(next);
    }
    std::printf("[ measured ] largest frame-to-frame change %.5f (allowed %.5f)\n", worst, allowed);
    EXPECT_LE(worst, allowed + 1e-5);
    EXPECT_GT(worst, allowed * 0.5) << "the TF does change along the path";
}

TEST(Keyframes, KeysMustBlend) {
    StylizerScene scene = test::smallForest();
    TransferFunction bigger = solidTf({1, 1, 1});
    bigger.width = 16;
    scene.keyframes = {{0, scene.camera, solidTf({1, 1, 1})}, {1, scene.camera, bigger}};
    EXPECT_THROW(scene.validate(), InvalidArgument);
    scene.keyframes[1].transferFunction = solidTf({1, 1, 1});
    scene.keyframes[1].time = 0;
    EXPECT_THROW(scene.validate(), InvalidArgument) << "keys by increasing time";
    EXPECT_THROW(sequenceTimes(0, 1, 0, 10), InvalidArgument);
    EXPECT_THROW(sequenceTimes(0, 100, 24, 10), InvalidArgument);
}

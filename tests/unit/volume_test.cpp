#include <gtest/gtest.h>

#include <iostream>
#include <limits>

#include "core/base/errors.h"
#include "core/volume/builtin_scenes.h"
#include "cli/scene_source.h"

using namespace volstyle;
using namespace volstyle::core;

TEST(Volume, ValidateNamesTheBadGrid) {
    Volume v({4, 4, 4}, Mat4::identity());
    EXPECT_NO_THROW(v.validate());
    v.extinction()[7] = -0.5f;
    EXPECT_THROW(v.validate(), InvalidArgument);
    v.extinction()[7] = std::numeric_limits<float>::quiet_NaN();
    try {
        v.validate();
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("'extinction'"), std::string::npos) << e.what();
    }
    v.extinction()[7] = 1;
    v.ensureAlbedo()[0] = 1.5f;  // albedo must stay in [0,1]
    EXPECT_THROW(v.validate(), InvalidArgument);
}

TEST(Volume, LimitsAndSingularTransforms) {
    Volume v({64, 64, 64}, Mat4::identity());
    EXPECT_THROW(v.validate(VolumeLimits{32 * 32 * 32, 1024}), InvalidArgument);
    v.setWorldFromIndex(Mat4::scale({1, 0, 1}));
    EXPECT_THROW(v.validate(), InvalidArgument);
    EXPECT_THROW(Volume({0, 4, 4}, Mat4::identity()), InvalidArgument);
}

TEST(Volume, WorldBoundsCoverTheVoxelBox) {
    Volume v({10, 20, 40}, unitBoxWorldFromIndex({10, 20, 40}));
    auto [lo, hi] = v.worldBounds();
    EXPECT_NEAR(lo.z, -1.0, 1e-12);
    EXPECT_NEAR(hi.z, 1.0, 1e-12);
    EXPECT_NEAR(hi.x - lo.x, 0.5, 1e-12);
    EXPECT_NEAR(v.voxelSize().y, 0.05, 1e-12);
}

TEST(BuiltinScenes, DeterministicAndSensible) {
    for (const auto& info : builtinScenes()) {
        Volume a = makeBuiltinScene(info.name, 24), b = makeBuiltinScene(info.name, 24);
        EXPECT_EQ(a.extinction(), b.extinction()) << info.name;
        EXPECT_NO_THROW(a.validate()) << info.name;
        auto [lo, hi] = Volume::range(a.extinction());
        EXPECT_GT(hi.x, 1.0f) << info.name << " is empty";
        EXPECT_GE(lo.x, 0.0f);
    }
    // The cloud has a flat base: nothing below y = -0.66, plenty just above it.
    Volume cloud = makeBuiltinScene("cloud", 64);
    auto at = [&](double y) {
        double sum = 0;
        int j = int((y + 1) / 2 * 64);
        for (int k = 0; k < 64; ++k)
            for (int i = 0; i < 64; ++i) sum += cloud.extinctionAt(i, j, k).x;
        return sum;
    };
    EXPECT_EQ(at(-0.75), 0.0);
    EXPECT_GT(at(-0.45), 1000.0);
}

TEST(BuiltinScenes, ClearErrors) {
    try {
        makeBuiltinScene("smoke", 32);
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("cloud, plume, sphere, cube"), std::string::npos) << e.what();
    }
    EXPECT_THROW(makeBuiltinScene("cloud", 4), InvalidArgument);
    EXPECT_THROW(makeBuiltinScene("cloud", 1000), InvalidArgument);
}

TEST(SceneSource, ParsesBuiltinSpecs) {
    EXPECT_EQ(cli::loadScene("builtin:cube:16").dims(), (Int3{16, 16, 16}));
    EXPECT_THROW(cli::loadScene("builtin:cube:abc"), InvalidArgument);
    EXPECT_THROW(cli::loadScene("builtin:cube:16x"), InvalidArgument);
    EXPECT_THROW(cli::loadScene("/nonexistent.vdb"), IoError);
}

TEST(BuiltinScenes, TheCloudsShortcutsChangeNoVoxel) {
    // makeCloud skips voxels its noise bound proves empty. This pins every bit of a 64³ cloud to
    // what it was before those shortcuts (FNV-1a of the extinction's bytes, recorded then; 37³ and
    // 128³ were checked the same way when they were added).
    const Volume cloud = makeBuiltinScene("cloud", 64);
    uint64_t hash = 1469598103934665603ull;
    const auto* bytes = reinterpret_cast<const unsigned char*>(cloud.extinction().data());
    for (size_t i = 0; i < cloud.extinction().size() * sizeof(float); ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
    std::cout << "[ measured ] cloud 64³ extinction FNV-1a " << std::hex << hash << std::dec << "\n";
    EXPECT_EQ(hash, 0x59603b903e397caaull);
}

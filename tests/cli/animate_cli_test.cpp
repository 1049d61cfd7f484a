// `volstyle animate` (issue #16; sparse frames, issue #39): key frames solved from painted views,
// the frames between them blended, every frame written and rendered.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "../unit/test_files.h"
#include "cli_run.h"
#include "core/image/image_io.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"
#include "core/volume/volume.h"

namespace fs = std::filesystem;
using namespace volstyle;

using test::lines;
using test::run;
using test::writeText;
using test::Result;

namespace {

/// Frame f of a ball of smoke moving +0.3 along x per frame; with `bright`, its right half emits.
core::Volume movingBall(int f, bool bright) {
    const Int3 dims{16, 16, 16};
    core::Volume v(dims, core::unitBoxWorldFromIndex(dims));
    auto& e = v.ensureEmission();
    for (int k = 0; k < 16; ++k)
        for (int j = 0; j < 16; ++j)
            for (int i = 0; i < 16; ++i) {
                const Vec3d x = v.worldFromIndex().applyPoint({double(i), double(j), double(k)});
                const Vec3d c(-0.3 + 0.3 * f, 0, 0);
                const size_t n = 3 * v.index(i, j, k);
                const bool in = length(x - c) < 0.45;
                for (int ch = 0; ch < 3; ++ch) {
                    v.extinction()[n + size_t(ch)] = in ? 3.0f : 0.0f;
                    e[n + size_t(ch)] = in && bright ? (x.x > c.x ? 1.0f : 0.2f) : 0.0f;
                }
            }
    return v;
}

}  // namespace

TEST(Cli, AnimatesKeyFramesAndRendersTheSequence) {
    auto dir = test::scratchDir();
    writeText(dir / "cam.json", R"({"eye": [0.3, 0.6, 2.8], "target": [0, 0, 0], "width": 24, "height": 24})");
    writeText(dir / "cam2.json", R"({"eye": [2.2, 0.5, 1.8], "target": [0, 0, 0], "width": 24, "height": 24})");
    writeText(dir / "dark.json", R"({"lights": [], "background": [0, 0, 0]})");
    std::string views;
    for (int f = 0; f <= 2; ++f) {
        core::saveVdb((dir / ("ball." + std::to_string(f) + ".vdb")).string(), movingBall(f, false));
        if (f == 1) continue;
        core::saveVdb((dir / ("truth." + std::to_string(f) + ".vdb")).string(), movingBall(f, true));
        for (const char* cam : {"cam", "cam2"}) {
            const std::string target = "t" + std::to_string(f) + cam + ".exr";
            Result r = run("render --scene " + (dir / ("truth." + std::to_string(f) + ".vdb")).string() + " --camera " + (dir / (std::string(cam) + ".json")).string() +
                           " --lighting " + (dir / "dark.json").string() + " -o " + (dir / target).string());
            ASSERT_EQ(r.status, 0) << r.out;
            // Painted as an artist's target: the picture (the background is black) with its
            // coverage as each pixel's weight, in a plain EXR (a render's own EXR would be read as
            // its picture, weight 1: docs/FORMATS.md).
            core::SaveOptions plain;
            plain.halfFloat = false;
            core::saveImage((dir / target).string(), core::loadImage((dir / target).string()).image, plain);
            views += std::string(views.empty() ? "" : ",") + R"({"frame": )" + std::to_string(f) + R"(, "camera": {"eye": )" +
                     (std::string(cam) == "cam" ? "[0.3, 0.6, 2.8]" : "[2.2, 0.5, 1.8]") +
                     R"(, "target": [0, 0, 0], "width": 24, "height": 24}, "target": ")" + target + "\"}";
        }
    }
    writeText(dir / "views.json", R"({"views": [)" + views + R"(], "lighting": {"lights": [], "background": [0, 0, 0]}})");
    const std::string frames = (dir / "ball.%d.vdb").string();
    Result r = run("animate --frames " + frames + " --range 0-2 --views " + (dir / "views.json").string() + " --iterations 20 -o " +
                   (dir / "out.%d.vdb").string() + " --render " + (dir / "r.%02d.png").string() + " --camera " + (dir / "cam.json").string());
    ASSERT_EQ(r.status, 0) << r.out;
    EXPECT_NE(r.out.find("sweep 3/3: key frame 2"), std::string::npos) << "progress: " << r.out;
    EXPECT_NE(r.out.find("frame 3/3"), std::string::npos) << r.out;
    for (int f = 0; f <= 2; ++f) EXPECT_TRUE(fs::exists(dir / ("r.0" + std::to_string(f) + ".png"))) << f;
    // The key frames carry the painted pattern (the ball's right half bright); frame 1, with no
    // views and no velocity in the files, is their blend voxel for voxel.
    const core::Volume k0 = core::loadVdb((dir / "out.0.vdb").string()), mid = core::loadVdb((dir / "out.1.vdb").string()),
                       k2 = core::loadVdb((dir / "out.2.vdb").string());
    ASSERT_TRUE(mid.hasEmission() && k0.hasEmission() && k2.hasEmission());
    double blendError = 0;
    for (size_t i = 0; i < mid.emission().size(); ++i)
        blendError = std::max(blendError, double(std::abs(mid.emission()[i] - 0.5f * (k0.emission()[i] + k2.emission()[i]))));
    EXPECT_LT(blendError, 1e-5);
    for (int f : {0, 2}) {
        const core::Volume& v = f == 0 ? k0 : k2;
        double right = 0, left = 0, nr = 0, nl = 0;
        for (int k = 0; k < 16; ++k)
            for (int j = 0; j < 16; ++j)
                for (int i = 0; i < 16; ++i) {
                    const size_t n = 3 * v.index(i, j, k);
                    if (v.extinction()[n] <= 0) continue;
                    const bool isRight = v.worldFromIndex().applyPoint({double(i), double(j), double(k)}).x > -0.3 + 0.3 * f;
                    (isRight ? right : left) += v.emission()[n];
                    (isRight ? nr : nl) += 1;
                }
        std::cout << "[ measured ] key frame " << f << ": right half " << right / nr << ", left half " << left / nl << " (truth 1 and 0.2)\n";
        EXPECT_GT(right / nr, 2 * (left / nl)) << f;
    }

    // The same frames stored as 8³ bricks (issue #39) give the same frames.
    Result sparse = run("animate --frames " + frames + " --range 0-2 --views " + (dir / "views.json").string() + " --iterations 20 --storage sparse -o " +
                        (dir / "sparse.%d.vdb").string() + " --quiet");
    ASSERT_EQ(sparse.status, 0) << sparse.out;
    for (int f = 0; f <= 2; ++f) {
        const core::Volume d = core::loadVdb((dir / ("out." + std::to_string(f) + ".vdb")).string()),
                           s = core::loadVdb((dir / ("sparse." + std::to_string(f) + ".vdb")).string());
        ASSERT_TRUE(d.dims() == s.dims() && s.hasEmission()) << f;
        double worst = 0;
        for (size_t i = 0; i < d.emission().size(); ++i) worst = std::max(worst, double(std::abs(d.emission()[i] - s.emission()[i])));
        EXPECT_LE(worst, 1e-5) << "frame " << f;
    }

    // Bad input: exit 2, one line naming the problem.
    for (const std::string& bad : {"animate --frames " + (dir / "ball.vdb").string() + " --range 0-2 --render " + (dir / "x.%d.png").string(),
                                   "animate --frames " + frames + " --range 2-0 --render " + (dir / "x.%d.png").string(),
                                   "animate --frames " + frames + " --range 0-2 -o " + (dir / "x.%d.vdb").string(),
                                   "animate --frames " + frames + " --range 0-1 --views " + (dir / "views.json").string() + " -o " + (dir / "x.%d.vdb").string()}) {
        Result b = run(bad);
        EXPECT_EQ(b.status, 2) << bad << "\n" << b.out;
        EXPECT_EQ(lines(b.out), 1u) << b.out;
    }
}

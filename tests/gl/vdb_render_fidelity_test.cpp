// A written VDB renders exactly like the volume it came from (issue #10): render(load(save(v)))
// equals render(v) to 1e-6 relative, for every built-in scene and for a solved volume.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/render/gpu_volume.h"
#include "core/solve/solver.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"
#include "../common/stamped_cloud.h"
#include "../unit/test_files.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

Camera smallCamera() {
    Camera c;
    c.eye = {0.4, 0.6, 3.2};
    c.width = c.height = 32;
    return c;
}

Lighting skyAndSun() {
    Lighting l;
    l.background.color = {0.2, 0.3, 0.5};
    return l;
}

/// Largest |a − b| / max(|a|, 1e-3) over every channel of every pixel.
double maxRelativeDifference(const Image& a, const Image& b) {
    EXPECT_EQ(a.rgba.size(), b.rgba.size());
    double worst = 0;
    for (size_t i = 0; i < std::min(a.rgba.size(), b.rgba.size()); ++i) {
        const double x = a.rgba[i], y = b.rgba[i];
        worst = std::max(worst, std::abs(x - y) / std::max(std::abs(x), 1e-3));
    }
    return worst;
}

Image renderOf(const Volume& v) {
    GpuVolume gpu(v);
    return test::sharedRenderer().render(gpu, smallCamera(), skyAndSun());
}

/// render(load(save(v))) against render(v).
double roundTripDifference(const Volume& v, const std::string& path) {
    saveVdb(path, v);
    const Volume back = loadVdb(path);
    EXPECT_EQ(back.dims(), v.dims()) << path;
    EXPECT_EQ(back.worldFromIndex(), v.worldFromIndex()) << path;
    return maxRelativeDifference(renderOf(v), renderOf(back));
}

}  // namespace

TEST(VdbRenderFidelity, EveryBuiltinSceneRendersTheSameFromItsFile) {
    VOLSTYLE_REQUIRE_GL();
    const auto dir = test::scratchDir();
    for (const auto& scene : builtinScenes()) {
        const Volume v = makeBuiltinScene(scene.name, 24);
        const double d = roundTripDifference(v, (dir / (scene.name + ".vdb")).string());
        std::printf("[ measured ] builtin:%s:24 render(load(save(v))) vs render(v): max relative difference %g\n",
                    scene.name.c_str(), d);
        EXPECT_LE(d, 1e-6) << scene.name;
    }
}

TEST(VdbRenderFidelity, ASolvedVolumeRendersTheSameFromItsFile) {
    VOLSTYLE_REQUIRE_GL();
    const auto dir = test::scratchDir();
    // Start from a file (so the solve writes into the file's grids), solve albedo toward stamped
    // letters from one view, and write the result.
    const std::string input = (dir / "input.vdb").string();
    saveVdb(input, test::thinCloud(20));
    const Volume start = loadVdb(input);
    Volume truth = start;
    truth.ensureAlbedo(0.9f);
    test::stampLetters(truth, truth.albedo(), {0.3f, 0.6f, 0.9f});
    SolveView view{"front", smallCamera(), renderOf(truth), std::nullopt};
    SolveOptions options;
    options.unknown = Unknown::Albedo;
    options.maxIterations = 6;
    Solver solver(test::device(), start, skyAndSun(), {view}, options);
    const Volume solved = solver.run().volume;
    ASSERT_TRUE(solved.hasAlbedo());
    const double d = roundTripDifference(solved, (dir / "solved.vdb").string());
    std::printf("[ measured ] solved volume: max relative difference %g\n", d);
    EXPECT_LE(d, 1e-6);
}

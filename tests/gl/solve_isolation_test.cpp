// A solve must not be disturbed by other GPU work between its iterations (issue #8): renders of
// other volumes and previews add light-depth volumes to the shared cache, which must never free
// or replace what a running solve has bound.
#include <gtest/gtest.h>

#include <cmath>

#include "core/render/gpu_volume.h"
#include "core/solve/solver.h"
#include "core/volume/builtin_scenes.h"
#include "../common/stamped_cloud.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

Lighting threeLights() {
    Lighting l;
    l.lights = {{{0.3, 1, 0.2}, {2.0, 1.8, 1.6}}, {{-1, 0.4, 0.3}, {0.8, 0.9, 1.2}}, {{0.2, -0.3, 1}, {0.5, 0.5, 0.5}}};
    l.background.color = {0.05, 0.05, 0.08};
    return l;
}

Camera cameraAt(Vec3d eye, int size) {
    Camera c;
    c.eye = eye;
    c.target = {0.01, -0.05, 0.02};
    c.width = c.height = size;
    return c;
}

/// An albedo solve with three lights toward a painted (stamped) albedo, from two views.
struct AlbedoProblem {
    Volume volume = test::thinCloud(20);
    Lighting lighting = threeLights();
    std::vector<SolveView> views;
    SolveOptions options;

    AlbedoProblem() {
        Volume truth = volume;
        truth.ensureAlbedo(0.9f);
        test::stampLetters(truth, truth.albedo(), {0.3f, 0.6f, 0.9f});
        GpuVolume gpu(truth);
        int n = 1;
        for (Vec3d eye : {Vec3d{0, 0.3, 3}, Vec3d{2.6, 0.5, 1.4}}) {
            Camera c = cameraAt(eye, 24);
            views.push_back({"v" + std::to_string(n++), c, test::sharedRenderer().render(gpu, c, lighting), std::nullopt});
        }
        options.unknown = Unknown::Albedo;
        options.maxIterations = 12;
        options.tolerance = 0;
        options.visibleChange = 0;
    }
};

double maxDifference(const std::vector<float>& a, const std::vector<float>& b) {
    double m = 0;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(double(a[i]) - double(b[i])));
    return m;
}

}  // namespace

TEST(SolveIsolation, OtherRendersAndPreviewsBetweenIterationsChangeNothing) {
    VOLSTYLE_REQUIRE_GL();
    AlbedoProblem problem;
    Solver alone(test::device(), problem.volume, problem.lighting, problem.views, problem.options);
    const SolveResult reference = alone.run();

    // The same solve, while "other sessions" render their own volumes under three other lights
    // and "a client" fetches previews of the current iterate (a fresh GPU copy each, as the
    // server did), between every two iterations.
    Volume other = makeBuiltinScene("plume", 16);
    Lighting otherLighting = threeLights();
    for (auto& l : otherLighting.lights) l.direction = Vec3d{l.direction.z, l.direction.x, -l.direction.y};
    Solver busy(test::device(), problem.volume, problem.lighting, problem.views, problem.options);
    int renders = 0;
    const SolveResult disturbed = busy.run([&](const SolveProgress&) {
        GpuVolume preview(busy.currentVolume());
        test::sharedRenderer().render(preview, problem.views[0].camera, problem.lighting);
        for (int i = 0; i < 3; ++i) {
            GpuVolume otherGpu(other);
            test::sharedRenderer().render(otherGpu, cameraAt({1.0 * i, 0.2, 3}, 12), otherLighting);
        }
        renders += 4;
    });
    ASSERT_GT(renders, 0);
    const double diff = maxDifference(reference.volume.albedo(), disturbed.volume.albedo());
    std::cout << "[ measured ] albedo difference with " << renders << " other renders between iterations: " << diff << "\n";
    EXPECT_LE(diff, 1e-5);
    EXPECT_EQ(reference.report.iterations, disturbed.report.iterations);
}

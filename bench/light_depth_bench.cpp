// bench/light_depth: how exact each way of getting the optical depth toward a light is (issue #34),
// on the float64 oracle (core/cpu_ref), against the exact light integral — a march from every
// sample itself at 0.05 voxel. Every image marches its view rays the same way (0.5 voxel, dense
// segments cut as march.glsl cuts them), so the differences are the light depth's alone. Schemes:
//   grid alone      rows a voxel apart, trilinear between nodes (the renderer before issue #34;
//                   the environment's lobes still use it)
//   default         a march from each sample over its first node spans, then the grid's node
//                   plane (rows half a voxel apart where a voxel holds ≥ 1 optical depth), read
//                   with a Catmull–Rom spline across the beam — what the renderer does
//   exact at 0.5    a march from every sample to the box at the view's step (the most a step of
//                   0.5 voxel can give)
// Then what a user sees: the renderer's scheme at default settings (step 0.5) and at step 0.25,
// against a converged single-scattering reference (view rays at 0.1 voxel, exact light at 0.05).
// GL time of each light pass and render: build/bin/render_bench. Usage: light_depth_bench [--quick]
// Prints two tables, then one JSON line per row.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "core/cpu_ref/agreement.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

struct Scene {
    const char* name;
    int res;
    double voxelDepth;
};

const std::pair<const char*, Vec3d> kSuns[] = {
    {"backlit", {0.15, 0.25, -1}}, {"side", {1, 0.2, 0.1}}, {"overhead", {0, 1, 0}}, {"grazing", {0.95, 0.12, -0.3}}};

/// One way of rendering that a table compares with its reference.
struct Column {
    const char* name;
    double step;
    cpu_ref::LightDepthMethod method;
};

std::string separator(size_t columns) {
    std::string s;
    for (size_t i = 0; i < columns; ++i) s += "---|";
    return s;
}

/// A table: each scene under each sun, every column against the reference (view step refStep,
/// exact light at 0.05), as markdown rows; their JSON lines are appended to `json`.
void table(const char* bench, const std::vector<Scene>& scenes, const Camera& cam, double refStep, const std::vector<Column>& columns,
           std::vector<std::string>& json) {
    std::printf("| scene | optical depth a voxel | sun |");
    for (const Column& c : columns) std::printf(" %s |", c.name);
    std::printf("\n|---|---|---|%s\n", separator(columns.size()).c_str());
    for (const Scene& sc : scenes) {
        const Volume v = cpu_ref::denseBuiltinScene(sc.name, sc.res, sc.voxelDepth);
        const double voxelDepth = maxComponent(Volume::range(v.extinction()).second) * length(v.worldFromIndex().applyVector({1, 0, 0}));
        for (const auto& [sunName, dir] : kSuns) {
            Lighting l;
            l.lights = {{dir, {10, 10, 10}}};
            l.background.color = {0, 0, 0};
            const Image reference = cpu_ref::renderReference<double>(v, cam, l, refStep, cpu_ref::LightDepthMethod::Exact, 0.05);
            std::printf("| %s %d³ | %.2f | %s |", sc.name, sc.res, voxelDepth, sunName);
            for (const Column& c : columns) {
                const cpu_ref::Agreement e = cpu_ref::agreement(cpu_ref::renderReference<double>(v, cam, l, c.step, c.method), reference);
                std::printf(" %.4f / %.2f%% |", e.sumRatio, 100 * e.relativeRms);
                char line[320];
                std::snprintf(line, sizeof line,
                              "{\"bench\":\"%s\",\"scene\":\"%s\",\"resolution\":%d,\"voxel_depth\":%.3f,\"sun\":\"%s\",\"scheme\":\"%s\","
                              "\"sum_ratio\":%.5f,\"relative_rms\":%.5f}",
                              bench, sc.name, sc.res, voxelDepth, sunName, c.name, e.sumRatio, e.relativeRms);
                json.push_back(line);
            }
            std::printf("\n");
            std::fflush(stdout);
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && !std::strcmp(argv[1], "--quick");
    const std::vector<Scene> scenes = quick ? std::vector<Scene>{{"cloud", 32, 4.0}}
                                            : std::vector<Scene>{{"cloud", 48, 4.0}, {"cloud", 24, 0}, {"cloud", 64, 0}, {"cloud", 32, 0.6}, {"plume", 48, 0}};
    Camera cam;
    cam.eye = {0.3, 0.4, 2.9};
    cam.target = {0, -0.05, 0};
    cam.fovYDeg = 40;
    cam.width = cam.height = quick ? 16 : 24;
    std::vector<std::string> json;
    std::printf("light depth against the exact light integral (float64 oracle, %dx%d, view step 0.5 voxel): image sum ratio / relative RMS\n\n",
                cam.width, cam.height);
    table("light_depth", scenes, cam, 0.5,
          {{"grid alone", 0.5, cpu_ref::LightDepthMethod::GridAlone}, {"default", 0.5, cpu_ref::LightDepthMethod::Grid},
           {"exact at 0.5", 0.5, cpu_ref::LightDepthMethod::Exact}},
          json);
    std::printf("\nwhat a user sees, against a converged reference (view step 0.1 voxel, exact light at 0.05): image sum ratio / relative RMS\n\n");
    table("light_depth_converged", scenes, cam, 0.1,
          {{"step 0.5 (default)", 0.5, cpu_ref::LightDepthMethod::Grid}, {"step 0.25", 0.25, cpu_ref::LightDepthMethod::Grid}}, json);
    std::printf("\n");
    for (const auto& line : json) std::printf("%s\n", line.c_str());
    return 0;
}

// bench/light_depth: how exact each way of getting the optical depth toward a light is (issue #34),
// on the float64 oracle (core/cpu_ref), against the exact light integral — a march from every
// sample itself at 0.05 voxel. Every image marches its view rays the same way (0.5 voxel), so the
// differences are the light depth's alone. Schemes:
//   grid alone      rows a voxel apart, trilinear between nodes (the renderer before issue #34;
//                   the environment's lobes still use it)
//   default         a march from each sample over its first node spans, then the grid (rows half a
//                   voxel apart where a voxel holds ≥ 0.25 optical depth) — what the renderer does
//   exact at 0.5    a march from every sample to the box at the view's step (the most a step of
//                   0.5 voxel can give)
// GL time of each light pass and render: build/bin/render_bench. Usage: light_depth_bench [--quick]
// Prints a table, then one JSON line per row.
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

/// The built-in scene scaled so that its densest voxel holds `voxelDepth` optical depths (0: as it is).
Volume sceneOf(const char* name, int res, double voxelDepth) {
    Volume v = makeBuiltinScene(name, res);
    if (voxelDepth > 0) cpu_ref::scaleToVoxelDepth(v, voxelDepth);
    for (float& a : v.ensureAlbedo()) a = 0.9f;
    return v;
}

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && !std::strcmp(argv[1], "--quick");
    struct Scene {
        const char* name;
        int res;
        double voxelDepth;
    };
    const std::vector<Scene> scenes = quick ? std::vector<Scene>{{"cloud", 32, 4.0}}
                                            : std::vector<Scene>{{"cloud", 48, 4.0}, {"cloud", 24, 0}, {"cloud", 64, 0}, {"cloud", 32, 0.6}, {"plume", 48, 0}};
    const std::pair<const char*, Vec3d> suns[] = {
        {"backlit", {0.15, 0.25, -1}}, {"side", {1, 0.2, 0.1}}, {"overhead", {0, 1, 0}}, {"grazing", {0.95, 0.12, -0.3}}};
    const std::pair<const char*, cpu_ref::LightDepthMethod> schemes[] = {
        {"grid alone", cpu_ref::LightDepthMethod::GridAlone}, {"default", cpu_ref::LightDepthMethod::Grid}, {"exact at 0.5", cpu_ref::LightDepthMethod::Exact}};
    Camera cam;
    cam.eye = {0.3, 0.4, 2.9};
    cam.target = {0, -0.05, 0};
    cam.fovYDeg = 40;
    cam.width = cam.height = quick ? 24 : 40;
    std::printf("light depth against the exact light integral (float64 oracle, %dx%d, view step 0.5 voxel): image sum ratio / relative RMS\n\n",
                cam.width, cam.height);
    std::printf("| scene | optical depth a voxel | sun | grid alone | default | exact at 0.5 |\n|---|---|---|---|---|---|\n");
    std::vector<std::string> json;
    for (const Scene& sc : scenes) {
        const Volume v = sceneOf(sc.name, sc.res, sc.voxelDepth);
        const double voxelDepth = maxComponent(Volume::range(v.extinction()).second) * length(v.worldFromIndex().applyVector({1, 0, 0}));
        for (const auto& [sunName, dir] : suns) {
            Lighting l;
            l.lights = {{dir, {10, 10, 10}}};
            l.background.color = {0, 0, 0};
            const Image exact = cpu_ref::renderReference<double>(v, cam, l, 0.5, cpu_ref::LightDepthMethod::Exact, 0.05);
            std::printf("| %s %d³ | %.2f | %s |", sc.name, sc.res, voxelDepth, sunName);
            for (const auto& [schemeName, method] : schemes) {
                const cpu_ref::Agreement e = cpu_ref::agreement(cpu_ref::renderReference<double>(v, cam, l, 0.5, method), exact);
                std::printf(" %.4f / %.2f%% |", e.sumRatio, 100 * e.relativeRms);
                char line[320];
                std::snprintf(line, sizeof line,
                              "{\"bench\":\"light_depth\",\"scene\":\"%s\",\"resolution\":%d,\"voxel_depth\":%.3f,\"sun\":\"%s\",\"scheme\":\"%s\","
                              "\"sum_ratio\":%.5f,\"relative_rms\":%.5f}",
                              sc.name, sc.res, voxelDepth, sunName, schemeName, e.sumRatio, e.relativeRms);
                json.push_back(line);
            }
            std::printf("\n");
            std::fflush(stdout);
        }
    }
    std::printf("\n");
    for (const auto& line : json) std::printf("%s\n", line.c_str());
    return 0;
}

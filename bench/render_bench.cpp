// bench/render: ms per frame of the single-scattering renderer on the built-in cloud at 480×480,
// for 32³–256³ volumes and steps of 0.25–2 voxels, with empty-space skipping on and off (the
// ratio is the figure) and the error each shortcut adds:
//   skip_err  — skipping on vs off (0 by construction: only zero-extinction segments are skipped)
//   term_err  — early termination at T < 1e-5 vs marching to the end
//   step_err  — relative RMS against the 0.25-voxel render of the same volume
//   hw_ms / hw_err — the texture unit's trilinear filter instead of 8 texel fetches
// Then the light-depth volumes alone (issue #10): build ms per resolution and sun direction
// (overhead, the default diagonal, grazing), with the grid's nodes and bytes.
// Usage: render_bench [--quick] [--lights-only] [--reps N] [--resolutions 64,128,256] [--steps 0.5,1]
//        [--voxel-depth D] (frames of the cloud scaled so its densest voxel holds D optical depths).
// Prints tables, then one JSON line per row.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstring>
#include <iostream>
#include <map>
#include <sstream>

#include "bench_util.h"
#include "core/cpu_ref/agreement.h"
#include "core/render/gpu_volume.h"
#include "core/render/light_grid.h"
#include "core/render/renderer.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

struct Row {
    int res;
    double step;
    double msSkip, msNoSkip, msHw, gpuMsSkip, lightMs;
    double skipErr, termErr, stepErr, hwErr;
};

Lighting benchLighting() {
    Lighting l;
    l.lights = {{{-0.55, 0.65, 0.55}, {26, 24.5, 22}}};
    l.background.color = {0.32, 0.5, 0.82};
    l.phase = {PhaseType::HenyeyGreenstein, 0.25};
    return l;
}

struct LightRow {
    int res;
    const char* sun;
    double ms;
    Int3 nodes;
    double mib;
};

/// Light-depth build time alone: a fresh GpuVolume per run (a new extinction version, so nothing
/// is cached) rendered to one pixel, timing only the light pass (stats.lightMs).
std::vector<LightRow> benchLightVolumes(Renderer& renderer, const std::vector<int>& resolutions, int reps) {
    const std::pair<const char*, Vec3d> suns[] = {
        {"overhead", {0, 1, 0}}, {"diagonal", {-0.55, 0.65, 0.55}}, {"grazing", {0.95, 0.12, -0.3}}};
    Camera pixel;
    pixel.eye = {0, 0.15, 3.4};
    pixel.width = pixel.height = 1;
    std::vector<LightRow> rows;
    for (int res : resolutions) {
        const Volume cloud = makeBuiltinScene("cloud", res);
        for (const auto& [name, dir] : suns) {
            Lighting l;
            l.lights = {{dir, {20, 20, 20}}};
            std::vector<double> ms;
            for (int r = 0; r < reps + 1; ++r) {  // the first run compiles
                GpuVolume volume(cloud);
                RenderStats stats;
                renderer.render(volume, pixel, l, {}, &stats);
                if (r > 0) ms.push_back(stats.lightMs);
            }
            const double across = lightGridAcross(maxVoxelDepth(maxComponent(Volume::range(cloud.extinction()).second), cloud.worldFromIndex()));
            const LightGrid g = makeLightGrid(cloud.dims(), cloud.worldFromIndex().inverseAffine(), normalize(dir), across);
            rows.push_back({res, name, bench::median(ms), g.dims, double(g.dims.volume()) * 4 / (1 << 20)});  // R32F: grey cloud
            std::cerr << "l" << std::flush;
        }
    }
    return rows;
}

void printLightVolumes(const std::vector<LightRow>& rows, int reps, const std::string& renderer) {
    std::printf("light-depth volumes: builtin cloud, one sun, step 0.5 voxel, median of %d builds\n\n", reps);
    std::printf("| volume | sun | build ms | grid nodes | MiB |\n|---|---|---|---|---|\n");
    for (const LightRow& r : rows)
        std::printf("| %d³ | %s | %.1f | %dx%dx%d | %.1f |\n", r.res, r.sun, r.ms, r.nodes.x, r.nodes.y, r.nodes.z, r.mib);
    std::printf("\n");
    for (const LightRow& r : rows)
        std::printf("{\"bench\":\"light_volume\",\"renderer\":\"%s\",\"resolution\":%d,\"sun\":\"%s\",\"build_ms\":%.2f,"
                    "\"nodes\":%lld,\"mib\":%.2f}\n",
                    renderer.c_str(), r.res, r.sun, r.ms, (long long)r.nodes.volume(), r.mib);
    std::printf("\n");
}

/// "64,128,256" → {64, 128, 256}.
std::vector<double> numberList(const char* text) {
    std::vector<double> out;
    std::stringstream in(text);
    for (std::string item; std::getline(in, item, ',');) out.push_back(std::stod(item));
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    bool quick = false, lightsOnly = false;
    int reps = 3;
    std::vector<double> chosenResolutions, chosenSteps;
    double voxelDepth = 0;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--quick")) quick = true;
        if (!std::strcmp(argv[i], "--lights-only")) lightsOnly = true;
        if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
        if (!std::strcmp(argv[i], "--resolutions") && i + 1 < argc) chosenResolutions = numberList(argv[++i]);
        if (!std::strcmp(argv[i], "--steps") && i + 1 < argc) chosenSteps = numberList(argv[++i]);
        if (!std::strcmp(argv[i], "--voxel-depth") && i + 1 < argc) voxelDepth = std::atof(argv[++i]);
    }
    spdlog::set_level(spdlog::level::warn);
    auto device = GpuDevice::create();
    Renderer renderer(*device);
    Camera cam;
    cam.eye = {0, 0.15, 3.4};
    cam.target = {0, -0.05, 0};
    cam.fovYDeg = 38;
    cam.width = cam.height = 480;
    const Lighting lighting = benchLighting();

    std::vector<int> resolutions = quick ? std::vector<int>{32, 64} : std::vector<int>{32, 64, 128, 256};
    std::vector<double> steps = quick ? std::vector<double>{0.5, 1} : std::vector<double>{0.25, 0.5, 1, 2};
    if (!chosenResolutions.empty()) resolutions.assign(chosenResolutions.begin(), chosenResolutions.end());
    if (!chosenSteps.empty()) steps = chosenSteps;
    const std::vector<LightRow> lightRows = benchLightVolumes(renderer, resolutions, reps);
    std::vector<Row> rows;
    for (int res : lightsOnly ? std::vector<int>{} : resolutions) {
        Volume cloud = makeBuiltinScene("cloud", res);
        if (voxelDepth > 0) cpu_ref::scaleToVoxelDepth(cloud, voxelDepth);
        GpuVolume volume(cloud);
        Image finest;
        for (double step : steps) {
            auto time = [&](RenderSettings s, Image* out, RenderStats* firstStats) {
                std::vector<double> wall, gpu;
                for (int r = 0; r < reps + 1; ++r) {  // the first run warms caches and compiles
                    RenderStats stats;
                    Image img = renderer.render(volume, cam, lighting, s, &stats);
                    if (r == 0) {
                        if (firstStats) *firstStats = stats;
                        if (out) *out = std::move(img);
                        continue;
                    }
                    wall.push_back(stats.totalMs);
                    gpu.push_back(stats.gpuMs);
                }
                return std::make_pair(bench::median(wall), bench::median(gpu));
            };
            RenderSettings skip, noSkip, full, hw;
            skip.stepVoxels = noSkip.stepVoxels = full.stepVoxels = hw.stepVoxels = step;
            noSkip.skipEmptySpace = false;
            full.terminationThreshold = 0;
            hw.hardwareFilter = true;
            Image imgSkip, imgNoSkip, imgFull, imgHw;
            RenderStats first;
            Row row{res, step, 0, 0, 0, 0, 0, 0, 0, 0, 0};
            auto [ms, gpuMs] = time(skip, &imgSkip, &first);
            row.msSkip = ms, row.gpuMsSkip = gpuMs, row.lightMs = first.lightMs;
            row.msNoSkip = time(noSkip, &imgNoSkip, nullptr).first;
            row.msHw = time(hw, &imgHw, nullptr).first;
            renderer.render(volume, cam, lighting, full, nullptr);
            imgFull = renderer.render(volume, cam, lighting, full, nullptr);
            row.skipErr = bench::maxRelativeError(imgSkip, imgNoSkip);
            row.termErr = bench::maxRelativeError(imgSkip, imgFull);
            row.hwErr = bench::maxRelativeError(imgHw, imgSkip);
            if (finest.empty()) finest = imgFull;
            row.stepErr = bench::relativeRms(imgSkip, finest);
            rows.push_back(row);
            std::cerr << "." << std::flush;
        }
    }
    std::cerr << "\n";

    const auto& caps = device->capabilities();
    std::printf("renderer: %s | %s | EGL %s\n", caps.renderer.c_str(), caps.version.c_str(), caps.platform.c_str());
    printLightVolumes(lightRows, reps, caps.renderer);
    if (lightsOnly) return 0;
    std::printf("scene: builtin cloud%s, 480x480, 1 sun, median of %d runs (wall ms incl. readback)\n\n",
                voxelDepth > 0 ? (" scaled to " + std::to_string(voxelDepth) + " optical depths a voxel").c_str() : "", reps);
    std::printf("| volume | step (vox) | ms skip | ms no-skip | speed-up | gpu ms | light-vol ms | skip err | term err | step err (RMS) | ms hw-filter | hw err |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const Row& r : rows)
        std::printf("| %d³ | %.2f | %.1f | %.1f | %.2fx | %s | %.1f | %.1e | %.1e | %.1e | %.1f | %.1e |\n", r.res, r.step,
                    r.msSkip, r.msNoSkip, r.msNoSkip / r.msSkip,
                    caps.isSoftware ? "n/a" : std::to_string(r.gpuMsSkip).substr(0, 6).c_str(),  // llvmpipe's timer reads ~0
                    r.lightMs, r.skipErr, r.termErr, r.stepErr, r.msHw, r.hwErr);
    std::printf("\n");
    for (const Row& r : rows)
        std::printf("{\"bench\":\"render\",\"renderer\":\"%s\",\"resolution\":%d,\"step_voxels\":%g,\"ms_skip\":%.2f,"
                    "\"ms_no_skip\":%.2f,\"skip_speedup\":%.3f,\"gpu_ms\":%.2f,\"light_volume_ms\":%.2f,\"skip_error\":%.3g,"
                    "\"termination_error\":%.3g,\"step_rms_error\":%.3g,\"ms_hw_filter\":%.2f,\"hw_filter_error\":%.3g}\n",
                    caps.renderer.c_str(), r.res, r.step, r.msSkip, r.msNoSkip, r.msNoSkip / r.msSkip, r.gpuMsSkip,
                    r.lightMs, r.skipErr, r.termErr, r.stepErr, r.msHw, r.hwErr);
    return 0;
}

// bench/lights: light reconstruction (issue #13), the counterpart of the TVCG paper's Fig. 5.
//
// Problem: the built-in cloud thinned to optical depth ~3, lit by a smooth procedural sky (a warm
// sun-like lobe, a blue sky, a green ground) fitted to 256 lobes — the "true" lighting; targets are
// its renderings; the solve starts from a black environment.
//   Part 1 (Fig. 5): lobes 16/64/256 × light-volume resolution 32³/64³/128³: the light volumes'
//           precomputation (s), seconds per CGLS iteration (one T, one Tᵀ, host work), their
//           memory (MB), beside the paper's (GTX 560 Ti; 128³ extinction, 10 views of 640×360).
//   Part 2 (time against error): 4–256 lobes solved to convergence: time and the targets' RMS
//           relative to their start; the error left is the basis's (a sky of 256 lobes seen
//           through N).
// Default scale for llvmpipe: the paper's 128³ extinction but 2 views of 160×90 (1/80 of its
// pixels; seconds per iteration scale with pixels); --paper runs the paper's 10 × 640×360 (hours
// on llvmpipe, minutes on a GPU); --quick 64³ and fewer cells.
// Usage: lights_bench [--paper] [--quick] [--skip-fig5]
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstring>

#include "../tests/common/stamped_cloud.h"
#include "bench_util.h"
#include "core/scene/environment_lobes.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/base/errors.h"
#include "core/solve/light_solver.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// The smooth sky: a lat-long map of 256×128.
std::shared_ptr<Image> proceduralSky() {
    auto img = std::make_shared<Image>(256, 128);
    const Vec3d sun = normalize(Vec3d(-0.5, 0.7, 0.5));
    for (int y = 0; y < img->height; ++y)
        for (int x = 0; x < img->width; ++x) {
            const Vec3d d = latLongDirection((x + 0.5) / img->width, (y + 0.5) / img->height);
            const double s = std::pow(std::max(0.0, dot(d, sun)), 8);
            const Vec3d c = Vec3d(6.0, 5.0, 3.5) * s + (d.y > 0 ? Vec3d(0.3, 0.5, 0.9) * (0.4 + 0.6 * d.y) : Vec3d(0.15, 0.2, 0.1));
            float* p = img->pixel(x, y);
            p[0] = float(c.x), p[1] = float(c.y), p[2] = float(c.z), p[3] = 1;
        }
    return img;
}

Lighting skyLighting(int lobes, int resolution, const std::shared_ptr<Image>& map) {
    Lighting l;
    l.lights.clear();
    l.background.color = {0.02, 0.02, 0.02};
    l.phase = {PhaseType::HenyeyGreenstein, 0.2};
    l.environment.lobes = lobes;
    l.environment.map = map;
    l.environment.lightVolumeResolution = resolution;
    return l;
}

}  // namespace

int main(int argc, char** argv) {
    bool paper = false, quick = false, skipFig5 = false;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--paper")) paper = true;
        else if (!std::strcmp(argv[i], "--quick")) quick = true;
        else if (!std::strcmp(argv[i], "--skip-fig5")) skipFig5 = true;
        else {
            std::fprintf(stderr, "usage: lights_bench [--paper] [--quick] [--skip-fig5]\n");
            return 2;
        }
    }
    spdlog::set_level(spdlog::level::warn);
    auto device = GpuDevice::create();
    Renderer renderer(*device);
    const int res = quick ? 64 : 128;
    const Volume cloud = test::thinCloud(res);
    const std::vector<Camera> cams = paper ? bench::orbitCameras(10, 640, 360) : bench::orbitCameras(2, 160, 90);
    const auto sky = proceduralSky();
    GpuVolume gpu(cloud);
    std::vector<SolveView> views;
    for (size_t i = 0; i < cams.size(); ++i)
        views.push_back({"v" + std::to_string(i), cams[i], renderer.render(gpu, cams[i], skyLighting(256, 64, sky)), std::nullopt});
    size_t pixels = 0;
    for (const Camera& c : cams) pixels += size_t(c.width) * c.height;
    std::printf("device: %s\n", device->capabilities().renderer.c_str());
    std::printf("Fig. 5: %d³ extinction, %zu views, %zu pixels; median of the iterations after the first\n\n", res, cams.size(), pixels);
    std::printf("| lobes | light volumes | precompute s | s / iteration | memory MiB | paper: precompute s | s / iteration | MB |\n");
    std::printf("|---|---|---|---|---|---|---|---|\n");
    // The paper's Fig. 5 (10 views of 640×360, 128³ extinction, 256 steps): 16/64/256 lobes ×
    // 32³/64³/128³ light volumes.
    const double paperPre[3][3] = {{0.2, 0.2, 0}, {0.78, 0.81, 1.07}, {3.72, 3.75, 5.39}};
    const double paperIt[3][3] = {{0.62, 0.63, 0.63}, {2.39, 2.44, 2.46}, {10.28, 10.28, 10.52}};
    const int paperMb[3][3] = {{2, 16, 128}, {8, 64, 512}, {32, 256, 2048}};
    std::vector<std::string> json;
    const std::vector<int> lobeCounts = quick ? std::vector<int>{16, 64} : std::vector<int>{16, 64, 256};
    const std::vector<int> resolutions = quick ? std::vector<int>{32} : std::vector<int>{32, 64, 128};
    for (size_t a = 0; a < lobeCounts.size() && !skipFig5; ++a)
        for (size_t b = 0; b < resolutions.size(); ++b) try {
            Lighting start = skyLighting(lobeCounts[a], resolutions[b], nullptr);
            start.environment.radiance.assign(size_t(lobeCounts[a]), Vec3d());
            SolveOptions opt;
            opt.maxIterations = 3;
            opt.tolerance = 0;
            std::vector<double> perIteration;
            LightSolver solver(*device, cloud, start, views, opt);
            const LightSolveResult r = solver.run([&](const SolveProgress& p) { perIteration.push_back(p.forwardMs + p.adjointMs); });
            perIteration.erase(perIteration.begin());
            const double it = bench::median(perIteration) / 1000;
            const int light = std::min(resolutions[b], res);
            const std::string pre = paperPre[a][b] > 0 ? std::to_string(paperPre[a][b]).substr(0, 4) : "—";  // blank in the paper
            std::printf("| %d | %d³ | %.2f | %.2f | %.0f | %s | %.2f | %d |\n", lobeCounts[a], light, r.lightVolumeMs / 1000, it,
                        double(r.lightVolumeBytes) / (1 << 20), pre.c_str(), paperIt[a][b], paperMb[a][b]);
            std::fflush(stdout);
            json.push_back("{\"table\":\"fig5\",\"lobes\":" + std::to_string(lobeCounts[a]) + ",\"light_volume\":" + std::to_string(light) +
                           ",\"precompute_s\":" + std::to_string(r.lightVolumeMs / 1000) + ",\"s_per_iteration\":" + std::to_string(it) +
                           ",\"memory_mib\":" + std::to_string(double(r.lightVolumeBytes) / (1 << 20)) + "}");
        } catch (const LimitExceeded& e) {  // over this GPU's buffer-texture limit: refused, as the API would
            std::printf("| %d | %d³ | refused: %s | | | | %.2f | %d |\n", lobeCounts[a], resolutions[b], e.what(), paperIt[a][b], paperMb[a][b]);
        }

    std::printf("\nTime against error: lobes solved to convergence (tolerance 1e-5, at most 30 iterations), light volumes 32³\n\n");
    std::printf("| lobes | iterations | s (with light volumes) | targets' RMS / start |\n|---|---|---|---|\n");
    for (int n : quick ? std::vector<int>{4, 16} : std::vector<int>{4, 16, 64}) {
        Lighting start = skyLighting(n, 32, nullptr);
        start.environment.radiance.assign(size_t(n), Vec3d());
        SolveOptions opt;
        opt.maxIterations = 30;
        opt.tolerance = 1e-5;
        const auto t0 = std::chrono::steady_clock::now();
        const LightSolveResult r = LightSolver(*device, cloud, start, views, opt).run();
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const double rel = bench::mean(r.report.finalRms) / bench::mean(r.report.initialRms);
        std::printf("| %d | %d | %.2f | %.4f |\n", n, r.report.iterations, s, rel);
        std::fflush(stdout);
        json.push_back("{\"table\":\"time_error\",\"lobes\":" + std::to_string(n) + ",\"iterations\":" + std::to_string(r.report.iterations) +
                       ",\"s\":" + std::to_string(s) + ",\"rms_over_start\":" + std::to_string(rel) + "}");
    }
    std::printf("\n");
    for (const auto& j : json) std::printf("%s\n", j.c_str());
    return 0;
}

// bench/refraction: what bending the rays costs (issue #16), on this machine's llvmpipe.
//   Render — the built-in cloud at 64³ seen at 256×256: no refractive grid, a constant one (the
//            straight kernels: the skip must show), a glass sphere with noise (paths traced on the
//            first render, cached on the next ones).
//   Solve  — the paper's Fig. 8: extinction through the glass from four 48×48 views, 40 iterations,
//            with and without the glass.
//   Step   — the tracing step against the path's error (exit point + direction, against RK4 at
//            a fiftieth of a voxel) and the trace time of a view, midpoint and Euler.
// Usage: refraction_bench [--quick]. Prints tables, then one JSON line per row.
#include <spdlog/spdlog.h>

#include <cstring>
#include <iostream>

#include "bench_util.h"
#include "core/base/stopwatch.h"
#include "core/gpu/gpu_device.h"
#include "core/render/curved_paths.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/solve/solver.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

double meanOf(const std::vector<double>& v) { return bench::mean(v); }

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && !std::strcmp(argv[1], "--quick");
    spdlog::set_level(spdlog::level::warn);
    auto device = GpuDevice::create();
    Renderer renderer(*device);
    std::cout << "device: " << device->capabilities().renderer << "\n";
    std::vector<std::string> json;

    // Render.
    const int res = quick ? 32 : 64, size = quick ? 128 : 256;
    Volume plain = makeBuiltinScene("cloud", res);
    Volume constant = plain;
    constant.refractiveIndex() = std::vector<float>(plain.voxelCount(), 1.33f);
    Volume glass = plain;
    addGlassSphere(glass, {});
    Lighting lighting;
    Camera cam = bench::orbitCameras(1, size, size)[0];
    std::cout << "\nRender: cloud " << res << "³, " << size << "x" << size << " (ms: first render, then median of 3 cached)\n";
    std::cout << "  grid            first   cached   trace   path vertices/ray\n";
    for (auto [name, volume] : {std::pair<const char*, const Volume*>{"none", &plain}, {"constant 1.33", &constant}, {"glass sphere", &glass}}) {
        GpuVolume gpu(*volume);
        RenderStats first;
        auto t0 = Clock::now();
        renderer.render(gpu, cam, lighting, {}, &first);
        const double firstMs = msSince(t0);
        std::vector<double> times;
        for (int i = 0; i < 3; ++i) {
            t0 = Clock::now();
            renderer.render(gpu, cam, lighting);
            times.push_back(msSince(t0));
        }
        double perRay = 0;
        if (gpu.refraction()) {
            const ViewPaths p = traceViewPaths(*gpu.refraction(), cam);
            perRay = double(p.vertices.size()) / double(size * size);
        }
        std::printf("  %-14s %6.0f %8.0f %7.0f %10.1f\n", name, firstMs, bench::median(times), first.refractionMs, perRay);
        json.push_back(std::string("{\"table\":\"render\",\"grid\":\"") + name + "\",\"first_ms\":" + std::to_string(firstMs) +
                       ",\"cached_ms\":" + std::to_string(bench::median(times)) + ",\"trace_ms\":" + std::to_string(first.refractionMs) +
                       ",\"vertices_per_ray\":" + std::to_string(perRay) + "}");
    }

    // Solve: Fig. 8.
    const int sres = quick ? 16 : 24, views = 4, vsize = quick ? 32 : 48;
    Volume truth = makeBuiltinScene("sphere", sres);
    addGlassSphere(truth, {1.3, 0.7, 2, 0.04, 3, 7});
    auto& e = truth.ensureEmission();
    e.assign(truth.voxelCount() * 3, 1.0f);
    Lighting dark;
    dark.lights.clear();
    dark.background.color = {0.1, 0.2, 0.5};
    GpuVolume truthGpu(truth);
    std::vector<SolveView> targets;
    for (const Camera& c : bench::orbitCameras(views, vsize, vsize))
        targets.push_back({"v" + std::to_string(targets.size()), c, renderer.render(truthGpu, c, dark), std::nullopt});
    std::cout << "\nSolve: extinction through glass (Fig. 8), " << sres << "³, " << views << " views of " << vsize << "², 40 iterations\n";
    std::cout << "  rays        s     RMS / start\n";
    for (bool bent : {false, true}) {
        Volume start = truth;
        start.extinction().assign(start.voxelCount() * 3, 0.0f);
        if (!bent) start.refractiveIndex().reset();
        SolveOptions opt;
        opt.unknown = Unknown::Extinction;
        opt.mediumRadiance = Vec3d(1, 1, 1);
        opt.maxIterations = 40;
        opt.tolerance = 0;
        const auto t0 = Clock::now();
        const SolveResult r = Solver(*device, start, dark, targets, opt).run();
        const double s = msSince(t0) / 1000;
        const double ratio = meanOf(r.report.finalRms) / meanOf(r.report.initialRms);
        std::printf("  %-9s %6.2f   %.4f\n", bent ? "curved" : "straight", s, ratio);
        json.push_back(std::string("{\"table\":\"solve\",\"rays\":\"") + (bent ? "curved" : "straight") + "\",\"seconds\":" + std::to_string(s) +
                       ",\"rms_ratio\":" + std::to_string(ratio) + "}");
    }

    // Step against error.
    Volume ball({48, 48, 48}, unitBoxWorldFromIndex({48, 48, 48}));
    addGlassSphere(ball, {1.4, 0.6, 4, 0.05, 3, 1});
    const auto grid = RefractiveGrid::of(ball);
    auto exitOf = [&](double step, RayScheme scheme) {
        const auto path = traceViewPath(*grid, {0.21, 0.13, -3.0}, {0.01, 0.02, 1}, 0, 1e30, {step, scheme});
        const auto& a = path[path.size() - 2];
        const auto& b = path.back();
        const Vec3d pa = grid->worldFromIndex().applyPoint(Vec3d(a.x, a.y, a.z)), pb = grid->worldFromIndex().applyPoint(Vec3d(b.x, b.y, b.z));
        return std::make_pair(pb, normalize(pb - pa));
    };
    const auto ref = exitOf(0.02, RayScheme::RungeKutta4);
    Camera view = bench::orbitCameras(1, 128, 128)[0];
    std::cout << "\nStep against error: a ray through a noisy glass ball (48³), and tracing a 128² view\n";
    std::cout << "  step (voxels)  midpoint error  Euler error  RK4 error   trace ms (midpoint)\n";
    for (double step : {1.0, 0.5, 0.25, 0.125, 0.0625}) {
        double err[3];
        int k = 0;
        for (RayScheme s : {RayScheme::Midpoint, RayScheme::EulerForward, RayScheme::RungeKutta4}) {
            const auto [x, d] = exitOf(step, s);
            err[k++] = length(x - ref.first) + length(d - ref.second);
        }
        PathTracing tracing;
        tracing.stepVoxels = step;
        const auto t0 = Clock::now();
        traceViewPaths(*grid, view, tracing);
        const double ms = msSince(t0);
        std::printf("  %12.4f  %14.2e  %11.2e  %9.2e   %8.0f\n", step, err[0], err[1], err[2], ms);
        json.push_back("{\"table\":\"step\",\"step\":" + std::to_string(step) + ",\"midpoint\":" + std::to_string(err[0]) +
                       ",\"euler\":" + std::to_string(err[1]) + ",\"rk4\":" + std::to_string(err[2]) + ",\"trace_ms\":" + std::to_string(ms) + "}");
    }
    std::cout << "\n";
    for (const auto& j : json) std::cout << j << "\n";
    return 0;
}

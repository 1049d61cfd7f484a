// bench/solver_race (issue #12): time to 10%, 1% and 0.1% of the start objective for the painting
// solver, per problem, with each iteration's split (forward, back-projection, vectors).
//   (a) a 48³ cloud (the stamped "VS" emission of bench/solver), emission only, 6 views of
//       96×96, no regularization, step 0.5 voxels.
// Then each problem's operators alone: one W a and one Wᵀ r (median of 5, after a warm-up), so
// the iterations' split reads as projections per iteration.
// Usage: solver_race [--iterations N]. Prints tables, then one JSON line per problem.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "../tests/common/stamped_cloud.h"
#include "bench_util.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/solve/gpu_vector.h"
#include "core/solve/projector.h"
#include "core/solve/solver.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

struct Problem {
    std::string name;
    int res, views, w, h;
    double step;
};

struct Race {
    std::vector<double> seconds, objective;  // after each iteration ([0]: the start, 0 s)
    double forwardMs = 0, adjointMs = 0, vectorMs = 0;
    int iterations = 0;
    /// Seconds of solving until the objective is at most `fraction` of the start (−1: never).
    double timeTo(double fraction) const {
        for (size_t i = 0; i < objective.size(); ++i)
            if (objective[i] <= fraction * objective[0]) return seconds[i];
        return -1;
    }
};

Race race(GpuDevice& device, Renderer& renderer, const Problem& p, int maxIterations) {
    Volume plain = test::thinCloud(p.res), truth = plain;
    test::stampLetters(truth, truth.ensureEmission(), Vec3(2.0f, 1.0f, 0.2f));
    std::vector<SolveView> views;
    {
        GpuVolume gpu(truth);
        RenderSettings s;
        s.stepVoxels = p.step;
        const auto cams = bench::orbitCameras(p.views, p.w, p.h);
        for (size_t i = 0; i < cams.size(); ++i)
            views.push_back({"v" + std::to_string(i), cams[i], renderer.render(gpu, cams[i], defaultLighting(), s), std::nullopt});
    }
    SolveOptions opt;
    opt.stepVoxels = p.step;
    opt.maxIterations = maxIterations;
    opt.tolerance = 0;  // run the iterations: the race reads the history
    opt.regularization.laplacian = 0;
    Race r;
    r.seconds.push_back(0);
    const SolveResult out = Solver(device, plain, defaultLighting(), views, opt).run([&](const SolveProgress& pr) {
        r.seconds.push_back((pr.forwardMs + pr.adjointMs + pr.vectorMs) / 1000.0 + r.seconds.back());
        r.forwardMs += pr.forwardMs, r.adjointMs += pr.adjointMs, r.vectorMs += pr.vectorMs;
    });
    r.objective = out.report.objectiveHistory;
    r.iterations = out.report.iterations;
    r.seconds.resize(r.objective.size(), r.seconds.back());
    return r;
}

struct OperatorTimes {
    double forwardMs = 0, adjointMs = 0;
    size_t pixels = 0, elements = 0;
};

double medianMs(const std::function<void()>& f, GpuDevice& device) {
    f();
    device.finish();
    std::vector<double> ms;
    for (int i = 0; i < 5; ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        device.finish();
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    return ms[2];
}

OperatorTimes operators(GpuDevice& device, const Problem& p) {
    Volume plain = test::thinCloud(p.res);
    GpuVolume gpu(plain);
    Projector W(device, gpu, defaultLighting(), Unknown::Emission, BasisType::Trilinear, plain.dims(), p.step);
    for (const Camera& c : bench::orbitCameras(p.views, p.w, p.h)) W.addView(c);
    GpuVector a(W.elementCount(), "race-a"), img(W.pixelCount(), "race-img");
    a.fill(1.0f);
    img.fill(1.0f);
    OperatorTimes t;
    t.pixels = W.pixelCount(), t.elements = W.elementCount();
    t.forwardMs = medianMs([&] { W.forward(a, img); }, device);
    img.fill(1.0f);
    t.adjointMs = medianMs([&] { W.adjoint(img, a); }, device);
    return t;
}

std::string seconds(double s) {
    char b[32];
    if (s < 0) return "not reached";
    std::snprintf(b, sizeof b, "%.2f", s);
    return b;
}

}  // namespace

int main(int argc, char** argv) {
    int maxIterations = 40;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--iterations") && i + 1 < argc) maxIterations = std::max(1, std::atoi(argv[++i]));
        else {
            std::fprintf(stderr, "usage: solver_race [--iterations N]\n");
            return 2;
        }
    }
    spdlog::set_level(spdlog::level::warn);
    auto device = GpuDevice::create();
    Renderer renderer(*device);
    std::printf("renderer: %s\n\n", device->capabilities().renderer.c_str());
    const std::vector<Problem> problems = {{"(a) 48³, 6 × 96², emission", 48, 6, 96, 96, 0.5}};
    std::printf("| problem | iterations | s to 10%% | s to 1%% | s to 0.1%% | ms/iter forward | back-proj | vectors |\n|---|---|---|---|---|---|---|---|\n");
    std::vector<std::string> json;
    for (const Problem& p : problems) {
        const Race r = race(*device, renderer, p, maxIterations);
        const int n = std::max(1, r.iterations);
        std::printf("| %s | %d | %s | %s | %s | %.0f | %.0f | %.0f |\n", p.name.c_str(), r.iterations, seconds(r.timeTo(0.1)).c_str(),
                    seconds(r.timeTo(0.01)).c_str(), seconds(r.timeTo(0.001)).c_str(), r.forwardMs / n, r.adjointMs / n, r.vectorMs / n);
        std::fflush(stdout);
        std::string j = "{\"bench\":\"solver_race\",\"problem\":\"" + p.name + "\",\"history\":[";
        for (size_t i = 0; i < r.objective.size(); ++i)
            j += (i ? "," : "") + std::string("[") + std::to_string(r.seconds[i]) + "," + std::to_string(r.objective[i] / r.objective[0]) + "]";
        json.push_back(j + "]}");
    }
    std::printf("\n| problem | pixels | unknowns | W a ms | Wᵀ r ms |\n|---|---|---|---|---|\n");
    for (const Problem& p : problems) {
        const OperatorTimes t = operators(*device, p);
        std::printf("| %s | %zu | %zu | %.0f | %.0f |\n", p.name.c_str(), t.pixels, t.elements, t.forwardMs, t.adjointMs);
    }
    std::printf("\n");
    for (const auto& j : json) std::printf("%s\n", j.c_str());
}

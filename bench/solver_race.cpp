// bench/solver_race (issue #12): time to 10%, 1% and 0.1% of the start objective for the painting
// solver, per problem, with each iteration's split (forward, back-projection, vectors).
//   (a) a 48³ cloud (the stamped "VS" emission of bench/solver), emission only, 6 views of
//       96×96, no regularization, step 0.5 voxels.
// Rows per problem: the solver as it is (preconditioned CGLS), without the preconditioner (as
// before issue #12), and coarse to fine (SolveOptions::coarseIterations = k: k iterations at half
// the unknowns, pixels and samples per axis, then the full problem from there), and matrix-free
// (SolveOptions::rowCacheBytes = 0: W and Wᵀ march every ray each time instead of gathering from
// the cached rows). "Seconds" are wall-clock from the solver's construction: its set-up (the
// rows' cache, the preconditioner, a coarse stage) counts, then the iterations' own time.
// Usage: solver_race [--iterations N]. Prints tables, then one JSON line per problem.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "../tests/common/stamped_cloud.h"
#include "bench_util.h"
#include "core/base/stopwatch.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
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
    std::vector<double> seconds, objective;  // after each iteration ([0]: the start, after the set-up)
    double setupSeconds = 0;
    double forwardMs = 0, adjointMs = 0, vectorMs = 0;
    int iterations = 0;
    /// Seconds of solving until the objective is at most `fraction` of `start` (−1: never).
    double timeTo(double fraction, double start) const {
        for (size_t i = 0; i < objective.size(); ++i)
            if (objective[i] <= fraction * start) return seconds[i];
        return -1;
    }
};

struct Setup {
    Volume plain;                 // where every solve starts
    std::vector<SolveView> views;  // renders of the stamped truth
};

Setup setUp(Renderer& renderer, const Problem& p) {
    Setup s{test::thinCloud(p.res), {}};
    Volume truth = s.plain;
    test::stampLetters(truth, truth.ensureEmission(), Vec3(2.0f, 1.0f, 0.2f));
    GpuVolume gpu(truth);
    RenderSettings rs;
    rs.stepVoxels = p.step;
    const auto cams = bench::orbitCameras(p.views, p.w, p.h);
    for (size_t i = 0; i < cams.size(); ++i)
        s.views.push_back({"v" + std::to_string(i), cams[i], renderer.render(gpu, cams[i], defaultLighting(), rs), std::nullopt});
    return s;
}

SolveOptions raceOptions(double step, int maxIterations) {
    SolveOptions opt;
    opt.stepVoxels = step;
    opt.maxIterations = maxIterations;
    opt.tolerance = 0;  // run the iterations: the race reads the history
    opt.regularization.laplacian = 0;
    return opt;
}

/// Solves from `start`.
Race solveRace(GpuDevice& device, const Volume& start, const std::vector<SolveView>& views, const SolveOptions& opt) {
    Race r;
    const auto t0 = Clock::now();
    Solver solver(device, start, defaultLighting(), views, opt);
    r.setupSeconds = msSince(t0) / 1000.0;
    r.seconds.push_back(r.setupSeconds);
    const SolveResult out = solver.run([&](const SolveProgress& pr) {
        r.seconds.push_back((pr.forwardMs + pr.adjointMs + pr.vectorMs) / 1000.0 + r.seconds.back());
        r.forwardMs += pr.forwardMs, r.adjointMs += pr.adjointMs, r.vectorMs += pr.vectorMs;
    });
    r.objective = out.report.objectiveHistory;
    r.iterations = out.report.iterations;
    r.seconds.resize(r.objective.size(), r.seconds.back());
    return r;
}

/// Coarse to fine through SolveOptions::coarseIterations: the history is the fine solve's,
/// starting after the coarse stage's whole time (its set-up included); [0] is the warm start.
Race coarseToFine(GpuDevice& device, const Setup& s, const Problem& p, int coarseIterations, int maxIterations) {
    SolveOptions opt = raceOptions(p.step, maxIterations);
    opt.coarseIterations = coarseIterations;
    Race r;
    std::vector<double> iterationSeconds;
    const auto t0 = Clock::now();
    Solver solver(device, s.plain, defaultLighting(), s.views, opt);
    const double fineSetup = msSince(t0) / 1000.0;
    SolveResult out = solver.run([&](const SolveProgress& pr) {
        iterationSeconds.push_back((pr.forwardMs + pr.adjointMs + pr.vectorMs) / 1000.0);
        r.forwardMs += pr.forwardMs, r.adjointMs += pr.adjointMs, r.vectorMs += pr.vectorMs;
    });
    r.setupSeconds = fineSetup + out.report.coarseMs / 1000.0;
    r.seconds.push_back(r.setupSeconds);
    for (double t : iterationSeconds) r.seconds.push_back(r.seconds.back() + t);
    r.objective = out.report.objectiveHistory;
    r.iterations = out.report.iterations;
    r.seconds.resize(r.objective.size(), r.seconds.back());
    return r;
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
    std::printf("| problem | iterations | set-up s | s to 10%% | s to 1%% | s to 0.1%% | ms/iter forward | back-proj | vectors |\n|---|---|---|---|---|---|---|---|---|\n");
    std::vector<std::string> json;
    for (const Problem& p : problems) {
        const Setup setup = setUp(renderer, p);
        const Race direct = solveRace(*device, setup.plain, setup.views, raceOptions(p.step, maxIterations));
        const double start = direct.objective[0];
        SolveOptions plainCgls = raceOptions(p.step, maxIterations);
        plainCgls.precondition = false;
        std::vector<std::pair<std::string, Race>> rows{{p.name, direct},
                                                       {p.name + ", no preconditioner", solveRace(*device, setup.plain, setup.views, plainCgls)}};
        SolveOptions matrixFree = raceOptions(p.step, maxIterations);
        matrixFree.rowCacheBytes = 0;
        rows.push_back({p.name + ", matrix-free", solveRace(*device, setup.plain, setup.views, matrixFree)});
        for (int k : {3, 6}) rows.push_back({p.name + ", coarse to fine (" + std::to_string(k) + " at half)", coarseToFine(*device, setup, p, k, maxIterations)});
        for (const auto& [name, r] : rows) {
            const int n = std::max(1, r.iterations);
            std::printf("| %s | %d | %.2f | %s | %s | %s | %.0f | %.0f | %.0f |\n", name.c_str(), r.iterations, r.setupSeconds,
                        seconds(r.timeTo(0.1, start)).c_str(),
                        seconds(r.timeTo(0.01, start)).c_str(), seconds(r.timeTo(0.001, start)).c_str(), r.forwardMs / n, r.adjointMs / n,
                        r.vectorMs / n);
            std::fflush(stdout);
            std::string j = "{\"bench\":\"solver_race\",\"problem\":\"" + name + "\",\"history\":[";
            for (size_t i = 0; i < r.objective.size(); ++i)
                j += (i ? "," : "") + std::string("[") + std::to_string(r.seconds[i]) + "," + std::to_string(r.objective[i] / start) + "]";
            json.push_back(j + "]}");
        }
    }
    std::printf("\n");
    for (const auto& j : json) std::printf("%s\n", j.c_str());
}

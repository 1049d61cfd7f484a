// bench/solver_race (issue #12): time to 10%, 1% and 0.1% of the start objective for the painting
// solver, per problem, with each iteration's split (forward, back-projection, vectors).
//   (a) a 48³ cloud (the stamped "VS" emission of bench/solver), emission only, 6 views of
//       96×96, no regularization, step 0.5 voxels.
// Rows per problem: the solver as it is (preconditioned CGLS), without the preconditioner (as
// before issue #12), and coarse to fine (SolveOptions::coarseIterations = k: k iterations at half
// the unknowns, pixels and samples per axis, then the full problem from there), and matrix-free
// (SolveOptions::rowCacheBytes = 0: W and Wᵀ march every ray each time instead of gathering from
// the cached rows). "Seconds" are wall-clock from the solver's construction: everything counts
// (set-up with the rows' cache and the preconditioner, the reach analysis, a coarse stage).
// Usage: solver_race [--iterations N] [--only a|b|c|ct|stroke] [--out DIR] [--write-problem DIR: (a) as
// files for volstyle solve, nothing run]. Prints tables, then one
// JSON line per row of (a); writes DIR/solver_race_{a,ct,b,c}.png (objective / start against
// seconds, log–log). Without --only: a, ct and stroke ((b) and (c) take minutes each).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "../tests/common/stamped_cloud.h"
#include "bench_util.h"
#include "core/image/image_io.h"
#include "log_plot.h"
#include "core/base/stopwatch.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/solve/solve_cache.h"
#include "core/solve/solve_prefetch.h"
#include "core/solve/solver.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"

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
    double rowsSeconds = 0;  // of the set-up: writing the rows of W
    std::string phases;      // the set-up phase by phase (SolveReport::setupPhases)
    double forwardMs = 0, adjointMs = 0, vectorMs = 0;
    int iterations = 0;
    /// Seconds of solving until the objective is at most `fraction` of `start` (−1: never).
    double timeTo(double fraction, double start) const {
        for (size_t i = 0; i < objective.size(); ++i)
            if (objective[i] <= fraction * start) return seconds[i];
        return -1;
    }
};

std::string fmtNumber(double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", x);
    return b;
}

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
    opt.visibleChange = 0;
    opt.regularization.laplacian = 0;
    return opt;
}

/// CGLS (the solver), or a baseline method over the same set-up (solver.h).
struct Method {
    std::optional<BaselineMethod> baseline;
    double rate = 0;
};

/// Solves from `start`, timing by the wall clock from the solver's construction: [0] is when the
/// first iteration starts (set-up, reach analysis, a coarse stage and the first residual done).
Race solveRace(GpuDevice& device, const Volume& start, const std::vector<SolveView>& views, const SolveOptions& opt,
               const Lighting& lighting = defaultLighting(), Method method = {}, SolveCache* cache = nullptr) {
    Race r;
    const auto t0 = Clock::now();
    Solver solver(device, start, lighting, views, opt, cache);
    double firstIterationMs = 0;
    auto progress = [&](const SolveProgress& pr) {
        if (r.seconds.empty()) firstIterationMs = pr.forwardMs + pr.adjointMs + pr.vectorMs;
        r.seconds.push_back(msSince(t0) / 1000.0);
        r.forwardMs += pr.forwardMs, r.adjointMs += pr.adjointMs, r.vectorMs += pr.vectorMs;
    };
    const SolveResult out = method.baseline ? solver.runBaseline(*method.baseline, opt.maxIterations, method.rate, progress)
                                            : solver.run(progress);
    r.setupSeconds = r.seconds.empty() ? msSince(t0) / 1000.0 : r.seconds.front() - firstIterationMs / 1000.0;
    r.seconds.insert(r.seconds.begin(), r.setupSeconds);
    r.rowsSeconds = out.report.rowCacheMs / 1000.0;
    for (const auto& [name, ms] : out.report.setupPhases) r.phases += (r.phases.empty() ? "" : ", ") + name + " " + std::to_string(int(std::lround(ms)));
    r.phases += "; rows kept " + std::to_string(out.report.rowCacheBytes >> 20) + " MiB";
    if (cache)
        r.phases += ", solve cache " + std::to_string(cache->bytes() >> 20) + " MiB in " + std::to_string(cache->entries()) + " entries, " +
                    std::to_string(cache->hits()) + " hits so far";
    r.objective = out.report.objectiveHistory;
    r.iterations = out.report.iterations;
    r.seconds.resize(r.objective.size(), r.seconds.back());
    return r;
}

/// A baseline at each of `rates`; the one whose last objective is lowest, named with its rate.
std::pair<std::string, Race> bestBaseline(GpuDevice& device, const Volume& start, const std::vector<SolveView>& views,
                                          const SolveOptions& opt, const Lighting& lighting, BaselineMethod method,
                                          const std::vector<double>& rates) {
    std::pair<std::string, Race> best;
    double bestRate = 0;
    std::string tried;
    for (double rate : rates) {
        Race r = solveRace(device, start, views, opt, lighting, {method, rate});
        tried += (tried.empty() ? "" : ", ") + fmtNumber(rate);
        if (best.second.objective.empty() || r.objective.back() < best.second.objective.back()) best.second = std::move(r), bestRate = rate;
    }
    best.first = std::string(method == BaselineMethod::Adam ? "Adam" : "SART") + ", rate " + fmtNumber(bestRate) + " (best of " + tried + ")";
    return best;
}

/// Objective / start against seconds for each row, log–log, coloured in the rows' order (red,
/// orange, blue, grey, purple, green, black), written to `path`.
void writePlot(const std::string& path, const std::vector<std::pair<std::string, Race>>& rows, double start) {
    const Vec3 colours[] = {{0.85f, 0.1f, 0.1f}, {0.95f, 0.55f, 0.0f}, {0.1f, 0.35f, 0.85f}, {0.55f, 0.55f, 0.55f},
                            {0.55f, 0.2f, 0.7f}, {0.1f, 0.6f, 0.2f}, {0.0f, 0.0f, 0.0f}};
    double xmin = 1e300, xmax = 0, ymin = 1e300;
    for (const auto& [name, r] : rows)
        for (size_t i = 0; i < r.objective.size(); ++i) {
            xmin = std::min(xmin, r.seconds[i]), xmax = std::max(xmax, r.seconds[i]);
            if (r.objective[i] > 0) ymin = std::min(ymin, r.objective[i] / start);
        }
    bench::LogPlot plot(std::max(xmin, 1e-3), xmax, std::max(ymin, 1e-12), 1.0);
    for (size_t k = 0; k < rows.size(); ++k) {
        std::vector<std::pair<double, double>> pts;
        for (size_t i = 0; i < rows[k].second.objective.size(); ++i) pts.push_back({rows[k].second.seconds[i], rows[k].second.objective[i] / start});
        plot.series(pts, colours[k % 7]);
    }
    saveImage(path, plot.img);
    std::printf("wrote %s\n", path.c_str());
}

Race coarseToFine(GpuDevice& device, const Setup& s, const Problem& p, int coarseIterations, int maxIterations) {
    SolveOptions opt = raceOptions(p.step, maxIterations);
    opt.coarseIterations = coarseIterations;
    return solveRace(device, s.plain, s.views, opt);
}

/// Issue #12's live loop: a converged solve, then one stroke on view 0 (a disc of 24 px radius
/// painted 30% brighter) and the re-solve from the solved volume: local (the default: only the
/// unknowns the stroke sees move), the whole problem with the first solve's cache
/// (solve_cache.h), and the whole problem without it. Default options (smoothing, tolerance,
/// bounds), as the page. Each row's end is measured by a fresh solver over the whole problem.
void strokeRace(GpuDevice& device, Renderer& renderer, const std::string& outDir) {
    const Problem p{"(c) 64³, 4 × 256², emission", 64, 4, 256, 256, 0.5};
    Setup s = setUp(renderer, p);
    SolveOptions opt;
    opt.stepVoxels = p.step;
    SolveCache cache;
    auto t0 = Clock::now();
    const SolveResult first = Solver(device, s.plain, defaultLighting(), s.views, opt, &cache).run();
    const double firstSeconds = msSince(t0) / 1000.0;
    {
        GpuVolume gpu(first.volume);
        RenderSettings rs;
        rs.stepVoxels = p.step;
        for (size_t v : {size_t(0), size_t(1)})
            saveImage(outDir + "/stroke_first_view" + std::to_string(v) + ".png", renderer.render(gpu, s.views[v].camera, defaultLighting(), rs));
    }
    Image& target = s.views[0].target;
    for (int y = 0; y < target.height; ++y)
        for (int x = 0; x < target.width; ++x)
            if (std::hypot(x - target.width / 2.0, y - target.height / 2.0) < 24)
                for (int c = 0; c < 3; ++c) target.pixel(x, y)[c] *= 1.3f;
    std::printf("\n| %s | solve | iterations | seconds | of which set-up | objective start → end | view 0 RMS start → end | moved unknowns | recomputed pixels |\n"
                "|---|---|---|---|---|---|---|---|---|\n", p.name.c_str());
    std::printf("| | first solve | %d | %.2f | | %.4g → %.4g | | %zu (all) | %zu (all) |\n", first.report.iterations, firstSeconds,
                first.report.initialObjective, first.report.finalObjective, first.report.hullCount, first.report.constraintPixels);
    // Each re-solve starts from the first solve's volume with the cache as the first solve left it.
    struct Way {
        const char* name;
        bool local, cached;
    };
    for (const Way& way : {Way{"re-solve after one stroke, local (the default)", true, true},
                           Way{"re-solve, whole problem, cache kept", false, true}, Way{"re-solve, whole problem, no cache", false, false}}) {
        SolveCache copy = cache;
        SolveOptions o = opt;
        o.localResolve = way.local;
        t0 = Clock::now();
        Solver again(device, first.volume, defaultLighting(), s.views, o, way.cached ? &copy : nullptr);
        const double setup = msSince(t0) / 1000.0;
        const SolveResult out = again.run();
        const double total = msSince(t0) / 1000.0;
        SolveOptions measure = opt;
        measure.maxIterations = 1;
        const SolveReport check = Solver(device, out.volume, defaultLighting(), s.views, measure).run().report;
        const SolveReport& r = out.report;
        // What an artist sees: the painted view and another one, rendered from each result.
        GpuVolume gpu(out.volume);
        RenderSettings rs;
        rs.stepVoxels = p.step;
        const std::string tag = way.local ? "local" : way.cached ? "whole" : "whole_nocache";
        for (size_t v : {size_t(0), size_t(1)})
            saveImage(outDir + "/stroke_" + tag + "_view" + std::to_string(v) + ".png", renderer.render(gpu, s.views[v].camera, defaultLighting(), rs));
        if (std::getenv("VOLSTYLE_RACE_HISTORY")) {
            for (double f : r.objectiveHistory) std::fprintf(stderr, "%.4g ", f);
            std::fprintf(stderr, " (rows %.0f ms; %.1f ms/iteration: forward %.1f, back-projection %.1f, vectors %.1f)\n", r.rowCacheMs, (total - setup) * 1000 / std::max(1, r.iterations),
                         r.forwardMs / std::max(1, r.iterations), r.adjointMs / std::max(1, r.iterations), r.vectorMs / std::max(1, r.iterations));
        }
        std::printf("| | %s | %d | %.2f | %.2f | %.4g → %.4g | %.4f → %.4f | %s | %s |\n", way.name, r.iterations, total, setup,
                    r.initialObjective, check.initialObjective, r.initialRms[0], check.initialRms[0],
                    r.local.active ? std::to_string(r.local.unknowns).c_str() : "all",
                    r.local.active ? std::to_string(r.local.pixels).c_str() : "all");
        std::fflush(stdout);
    }
}

std::string seconds(double s);

/// Issue #12's CT case: a 128×128 slice one voxel thick (two discs and a square hole of
/// extinction) under a constant medium radiance, 60 views of 128×1 around it (nearly parallel
/// rays: eyes 20 units away), extinction solved from zero. CGLS (cached rows and matrix-free)
/// against SART's 20 sweeps and Adam on the same operators: the time to 10%, 1%, 0.1% of the
/// start objective and to the objective SART's 20 sweeps reach (the issue: CGLS 71 s for 100
/// iterations; a textbook SART's 20 sweeps ~2.3 s).
void ctRace(GpuDevice& device, Renderer& renderer, const std::string& outDir) {
    const Int3 dims{128, 128, 1};
    Volume truth(dims, unitBoxWorldFromIndex(dims));
    const Vec3d Lm{1.0, 1.0, 1.0};
    auto& e = truth.ensureEmission();
    for (int j = 0; j < dims.y; ++j)
        for (int i = 0; i < dims.x; ++i) {
            const double x = (i + 0.5) / 64.0 - 1.0, y = (j + 0.5) / 64.0 - 1.0;
            double sigma = std::hypot(x, y) < 0.8 ? 2.0 : 0.0;
            if (std::hypot(x - 0.3, y + 0.2) < 0.25) sigma = 5.0;
            if (std::abs(x + 0.3) < 0.15 && std::abs(y - 0.25) < 0.15) sigma = 0.0;
            truth.setExtinction(i, j, 0, Vec3(float(sigma)));
        }
    for (size_t i = 0; i < truth.voxelCount(); ++i) e[3 * i] = e[3 * i + 1] = e[3 * i + 2] = 1.0f;
    Lighting light;
    light.lights.clear();
    light.background.color = {0.1, 0.2, 0.5};
    std::vector<SolveView> views;
    GpuVolume gpu(truth);
    for (int v = 0; v < 60; ++v) {
        const double a = std::numbers::pi * v / 60;
        Camera c;
        c.eye = {20 * std::cos(a), 20 * std::sin(a), 0};
        c.target = {0, 0, 0};
        c.up = {0, 0, 1};
        c.width = 128, c.height = 1;
        c.fovYDeg = 2 * std::atan(1.45 / (128 * 20.0)) * 180 / std::numbers::pi;
        views.push_back({"ct" + std::to_string(v), c, renderer.render(gpu, c, light), std::nullopt});
    }
    Volume start = truth;
    start.extinction().assign(start.voxelCount() * 3, 0.0f);
    auto options = [&](int iterations, bool cached) {
        SolveOptions opt = raceOptions(0.5, iterations);
        opt.unknown = Unknown::Extinction;
        opt.mediumRadiance = Lm;
        if (!cached) opt.rowCacheBytes = 0;
        return opt;
    };
    std::vector<std::pair<std::string, Race>> rows;
    rows.push_back(bestBaseline(device, start, views, options(20, true), light, BaselineMethod::Sart, {0.25, 0.5, 1.0}));
    rows.push_back({"CGLS, cached rows (the default)", solveRace(device, start, views, options(100, true), light)});
    rows.push_back({"CGLS, matrix-free", solveRace(device, start, views, options(100, false), light)});
    SolveOptions plain = options(100, true);
    plain.precondition = false;
    rows.push_back({"CGLS, no preconditioner", solveRace(device, start, views, plain, light)});
    rows.push_back(bestBaseline(device, start, views, options(100, true), light, BaselineMethod::Adam, {0.03, 0.1, 0.3}));
    const double f0 = rows[1].second.objective.front();
    const double sartEnd = rows[0].second.objective.back();
    std::printf("\n| CT: 128² slice, 60 views of 128×1, extinction | iterations | set-up s | s to 10%% | s to 1%% | s to 0.1%% | s to SART's 20 sweeps (%.2g) | s for all | objective at the end | ms/iter forward / back-proj / vectors |\n"
                "|---|---|---|---|---|---|---|---|---|---|\n", sartEnd / f0);
    for (const auto& [name, r] : rows) {
        const int n = std::max(1, r.iterations);
        std::printf("| %s | %d | %.2f | %s | %s | %s | %s | %.2f | %.2g of the start | %.1f / %.1f / %.1f |\n", name.c_str(), r.iterations,
                    r.setupSeconds, seconds(r.timeTo(0.1, f0)).c_str(), seconds(r.timeTo(0.01, f0)).c_str(),
                    seconds(r.timeTo(0.001, f0)).c_str(), seconds(r.timeTo(sartEnd / f0 * (1 + 1e-9), f0)).c_str(), r.seconds.back(),
                    r.objective.back() / f0, r.forwardMs / n, r.adjointMs / n, r.vectorMs / n);
        std::fflush(stdout);
    }
    writePlot(outDir + "/solver_race_ct.png", rows, f0);
}

/// The paper's configurations (issue #12's (b) and (c)): CGLS as it is (rows past the cache
/// budget stay matrix-free), then again with the first solve's cache (what a session's next
/// solve costs), against the best Adam of a small sweep; the time to 1% of the start RMS (1e-4
/// of the objective) and to 10/1/0.1% of the objective.
void paperRace(GpuDevice& device, Renderer& renderer, const Problem& p, int iterations, const std::string& outDir,
               const std::string& tag) {
    const Setup setup = setUp(renderer, p);
    std::vector<std::pair<std::string, Race>> rows;
    SolveCache cache;  // as the server keeps one: a session's next solve finds the rows and renders
    rows.push_back({"CGLS (the default)", solveRace(device, setup.plain, setup.views, raceOptions(p.step, iterations), defaultLighting(), {}, &cache)});
    rows.push_back({"CGLS, the next solve of the same views (the first one's cache kept, as the server does)",
                    solveRace(device, setup.plain, setup.views, raceOptions(p.step, iterations), defaultLighting(), {}, &cache)});
    // The server makes each view's renders and rows ahead of a session's first solve while the
    // artist paints (server/service/solve_prefetch.cpp): that solve then starts from them.
    SolveCache ahead;
    const PrefetchReport made = prefetchSolve(device, setup.plain, defaultLighting(), setup.views, raceOptions(p.step, iterations), ahead);
    std::fprintf(stderr, "%s: ahead of the first solve, %d views rendered and %d views' rows written, in %.0f ms\n", p.name.c_str(),
                 made.viewsRendered, made.rowsWritten, made.ms);
    rows.push_back({"CGLS, a first solve after the views were made ahead (the server, while the artist paints)",
                    solveRace(device, setup.plain, setup.views, raceOptions(p.step, iterations), defaultLighting(), {}, &ahead)});
    rows.push_back(bestBaseline(device, setup.plain, setup.views, raceOptions(p.step, iterations), defaultLighting(),
                                BaselineMethod::Adam, {0.03, 0.1}));
    const double f0 = rows[0].second.objective.front();
    std::printf("\n| %s | iterations | set-up s (rows) | s to 10%% | s to 1%% | s to 0.1%% | s to 1%% of the start RMS | s/iteration | ms/iter forward, back-proj, vectors | end |\n"
                "|---|---|---|---|---|---|---|---|---|---|\n", p.name.c_str());
    for (const auto& [name, r] : rows) {
        const double n = std::max(1, r.iterations);
        std::printf("| %s | %d | %.2f (%.2f) | %s | %s | %s | %s | %.2f | %.0f, %.0f, %.0f | %.2g of the start |\n", name.c_str(), r.iterations,
                    r.setupSeconds, r.rowsSeconds, seconds(r.timeTo(0.1, f0)).c_str(), seconds(r.timeTo(0.01, f0)).c_str(),
                    seconds(r.timeTo(0.001, f0)).c_str(), seconds(r.timeTo(1e-4, f0)).c_str(), (r.seconds.back() - r.setupSeconds) / n,
                    r.forwardMs / n, r.adjointMs / n, r.vectorMs / n, r.objective.back() / f0);
        std::fprintf(stderr, "%s: set-up (ms) %s\n", name.c_str(), r.phases.c_str());
        std::fflush(stdout);
    }
    writePlot(outDir + "/solver_race_" + tag + ".png", rows, f0);
}

/// Problem (a) as files for `volstyle solve` (the same start volume, float EXR targets, the
/// weights the race uses — each target's alpha — and the cameras), so the CLI's per-iteration
/// split can be compared with the race's on the same problem (issue #40).
void writeProblem(const Setup& setup, const std::string& dir) {
    std::filesystem::create_directories(dir);
    saveVdb(dir + "/start.vdb", setup.plain);
    SaveOptions exr;
    exr.halfFloat = false;
    std::string views;
    for (size_t i = 0; i < setup.views.size(); ++i) {
        const SolveView& v = setup.views[i];
        Image weights = v.target;
        for (size_t p = 0; p < weights.pixelCount(); ++p)
            for (int c = 0; c < 4; ++c) weights.rgba[4 * p + size_t(c)] = c == 3 ? 1.0f : v.target.rgba[4 * p + 3];
        saveImage(dir + "/" + v.name + ".exr", v.target, exr);
        saveImage(dir + "/" + v.name + "_weights.exr", weights, exr);
        const Camera& c = v.camera;
        char buf[512];
        std::snprintf(buf, sizeof buf,
                      "%s{\"name\": \"%s\", \"target\": \"%s.exr\", \"weights\": \"%s_weights.exr\", \"camera\": {\"eye\": [%.17g, %.17g, %.17g], "
                      "\"target\": [%.17g, %.17g, %.17g], \"up\": [%.17g, %.17g, %.17g], \"fov_y_deg\": %.17g, \"width\": %d, \"height\": %d}}",
                      i ? ",\n  " : "", v.name.c_str(), v.name.c_str(), v.name.c_str(), c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y,
                      c.target.z, c.up.x, c.up.y, c.up.z, c.fovYDeg, c.width, c.height);
        views += buf;
    }
    std::FILE* f = std::fopen((dir + "/views.json").c_str(), "w");
    std::fprintf(f, "{\"views\": [\n  %s\n]}\n", views.c_str());
    std::fclose(f);
    std::printf("wrote problem (a) to %s: volstyle solve --scene %s/start.vdb --views %s/views.json --unknowns emission --iterations 40 "
                "--tolerance 0 --visible-change 0 --regularization laplacian=0 -o OUT.vdb\n",
                dir.c_str(), dir.c_str(), dir.c_str());
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
    std::string only;  // empty: tables a, ct and stroke (b and c take minutes: only when asked)
    std::string outDir = "bench-results";
    std::string problemDir;  // --write-problem: problem (a) as files for volstyle solve
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--iterations") && i + 1 < argc) maxIterations = std::max(1, std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
        else if (!std::strcmp(argv[i], "--out") && i + 1 < argc) outDir = argv[++i];
        else if (!std::strcmp(argv[i], "--write-problem") && i + 1 < argc) problemDir = argv[++i];
        else {
            std::fprintf(stderr, "usage: solver_race [--iterations N] [--only a|b|c|ct|stroke] [--out DIR] [--write-problem DIR]\n");
            return 2;
        }
    }
    auto wanted = [&](const std::string& table) { return only.empty() ? table != "b" && table != "c" : only == table; };
    std::filesystem::create_directories(outDir);
    spdlog::set_level(spdlog::level::warn);
    auto device = GpuDevice::create();
    Renderer renderer(*device);
    std::printf("renderer: %s\n\n", device->capabilities().renderer.c_str());
    const std::vector<Problem> problems = {{"(a) 48³, 6 × 96², emission", 48, 6, 96, 96, 0.5}};
    if (!problemDir.empty()) {
        writeProblem(setUp(renderer, problems[0]), problemDir);
        return 0;
    }
    std::printf("| problem | iterations | set-up s (rows) | s to 10%% | s to 1%% | s to 0.1%% | ms/iter forward | back-proj | vectors |\n|---|---|---|---|---|---|---|---|---|\n");
    {  // compile every shader variant first: the first solve would otherwise pay for it
        const Setup warm = setUp(renderer, problems[0]);
        SolveOptions once = raceOptions(problems[0].step, 1);
        solveRace(*device, warm.plain, warm.views, once);
        once.rowCacheBytes = 0;
        solveRace(*device, warm.plain, warm.views, once);
        once.coarseIterations = 1;
        solveRace(*device, warm.plain, warm.views, once);
    }
    std::vector<std::string> json;
    for (const Problem& p : problems) {
        if (!wanted("a")) break;
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
        auto adam = bestBaseline(*device, setup.plain, setup.views, raceOptions(p.step, std::max(maxIterations, 60)), defaultLighting(),
                                 BaselineMethod::Adam, {0.01, 0.03, 0.1});
        rows.push_back({p.name + ", " + adam.first, adam.second});
        for (const auto& [name, r] : rows) {
            const int n = std::max(1, r.iterations);
            std::printf("| %s | %d | %.2f (%.2f) | %s | %s | %s | %.0f | %.0f | %.0f |\n", name.c_str(), r.iterations, r.setupSeconds, r.rowsSeconds,
                        seconds(r.timeTo(0.1, start)).c_str(),
                        seconds(r.timeTo(0.01, start)).c_str(), seconds(r.timeTo(0.001, start)).c_str(), r.forwardMs / n, r.adjointMs / n,
                        r.vectorMs / n);
            std::fprintf(stderr, "%s: set-up (ms) %s\n", name.c_str(), r.phases.c_str());
            std::fflush(stdout);
            std::string j = "{\"bench\":\"solver_race\",\"problem\":\"" + name + "\",\"history\":[";
            for (size_t i = 0; i < r.objective.size(); ++i)
                j += (i ? "," : "") + std::string("[") + std::to_string(r.seconds[i]) + "," + std::to_string(r.objective[i] / start) + "]";
            json.push_back(j + "]}");
        }
        writePlot(outDir + "/solver_race_a.png", rows, start);
    }
    // 256 steps along the volume's diagonal: 128·√3/256 voxels.
    if (wanted("b")) paperRace(*device, renderer, {"(b) 128³, 2 × 480², 256 steps per diagonal", 128, 2, 480, 480, 0.866}, maxIterations, outDir, "b");
    if (wanted("c")) paperRace(*device, renderer, {"(c) 128³, 10 × 640×360", 128, 10, 640, 360, 0.866}, maxIterations, outDir, "c");
    if (wanted("ct")) ctRace(*device, renderer, outDir);
    if (wanted("stroke")) strokeRace(*device, renderer, outDir);
    std::printf("\n");
    for (const auto& j : json) std::printf("%s\n", j.c_str());
}

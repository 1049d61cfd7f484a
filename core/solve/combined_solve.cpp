#include "core/solve/combined_solve.h"

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/solve/light_solver.h"
#include "core/solve/solver.h"

namespace volstyle::core {
namespace {

double mean(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x / double(v.size());
    return s;
}

}  // namespace

CombinedSolveResult solveLightsAndVolume(GpuDevice& device, const Volume& volume, const Lighting& lighting,
                                         const std::vector<SolveView>& views, const SolveOptions& volumeOptions, int rounds,
                                         const std::function<void(const CombinedProgress&)>& progress,
                                         const std::atomic<bool>* cancel) {
    if (volumeOptions.unknown == Unknown::Extinction)
        throw InvalidArgument("lights can be solved together with emission and/or albedo, not extinction");
    if (!lighting.environment.active())
        throw InvalidArgument("lights: the lighting has no environment lobes; set environment.lobes (1-256)");
    const auto t0 = Clock::now();
    CombinedSolveResult out;
    out.volume = volume;
    Lighting lit = lighting;
    SolveOptions volumeOpt = volumeOptions;
    volumeOpt.localResolve = false;  // each round changes the lighting: nothing to re-solve locally
    volumeOpt.analyzeReach = false;
    for (int round = 1; round <= std::max(1, rounds); ++round) {
        LightSolver lights(device, out.volume, lit, views, volumeOptions, cancel);
        const LightSolveResult l = lights.run([&](const SolveProgress& p) {
            if (progress) progress({round, "lights", p});
        }, cancel);
        if (out.rmsHistory.empty()) out.rmsHistory.push_back(mean(l.report.initialRms));
        out.rmsHistory.push_back(mean(l.report.finalRms));
        lit.environment.setRadiance(l.radiance);

        Solver solver(device, out.volume, lit, views, volumeOpt);
        SolveResult v = solver.run([&](const SolveProgress& p) {
            if (progress) progress({round, unknownName(volumeOpt.unknown), p});
        }, cancel);
        out.rmsHistory.push_back(mean(v.report.finalRms));
        out.volume = std::move(v.volume);
        out.rounds = round;
    }
    out.radiance = lit.environment.radiance;
    out.totalMs = msSince(t0);
    return out;
}

}  // namespace volstyle::core

#pragma once
/// \file stamped_problem.h
/// A small solve problem shared by the solver's speed and prefetch tests: the stamped cloud at
/// 24³ seen from 4 views of 32×32, targets rendered from its stamped emission.

#include <cmath>
#include <numbers>

#include "../common/stamped_cloud.h"
#include "core/render/gpu_volume.h"
#include "core/solve/solver.h"
#include "gl_test_env.h"

namespace volstyle::test {

struct Problem {
    core::Volume plain;
    std::vector<core::SolveView> views;
};

/// The stamped cloud at 24³ seen from 4 views of 32×32: small enough for many iterations.
inline Problem stampedProblem() {
    Problem p{test::thinCloud(24), {}};
    core::Volume truth = p.plain;
    test::stampLetters(truth, truth.ensureEmission(), Vec3(2.0f, 1.0f, 0.2f));
    core::GpuVolume gpu(truth);
    for (int i = 0; i < 4; ++i) {
        const double a = 0.3 + 2 * std::numbers::pi * i / 4;
        core::Camera c;
        c.eye = {3.0 * std::sin(a), 0.4 * std::cos(3 * a) + 0.013, 3.0 * std::cos(a)};
        c.target = {0.011, -0.07, 0.013};
        c.fovYDeg = 42;
        c.width = c.height = 32;
        p.views.push_back({"v" + std::to_string(i), c, test::sharedRenderer().render(gpu, c, core::defaultLighting()), std::nullopt});
    }
    return p;
}

inline core::SolveOptions plainOptions(int iterations) {
    core::SolveOptions opt;
    opt.regularization.laplacian = 0;
    opt.maxIterations = iterations;
    opt.tolerance = 0;
    opt.visibleChange = 0;
    return opt;
}

}  // namespace volstyle::test

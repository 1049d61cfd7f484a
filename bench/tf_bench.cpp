// bench/tf: compiling transfer-function layers (issue #15): a solid base, a gradient and a
// diffusion layer of 5 constraints, per TF size 64²–512²: ms, CG iterations (all four channels),
// the relative residual reached.
#include <chrono>
#include <cstdio>

#include "core/stylize/tf_layers.h"

using namespace volstyle::core;

int main() {
    TfLayer base;
    base.solid = {0, 0, {1, 1, 1}, 1};
    TfLayer ramp;
    ramp.kind = TfLayerKind::Gradient;
    ramp.blend = TfBlend::Multiply;
    ramp.from = {0, 0, {1, 0.6, 0.3}, 1};
    ramp.to = {1, 1, {0.3, 0.5, 1}, 1};
    TfLayer spots;
    spots.kind = TfLayerKind::Diffusion;
    spots.constraints = {{0.1, 0.2, {1, 0, 0}, 1}, {0.8, 0.3, {0, 1, 0}, 0.5}, {0.5, 0.9, {0, 0, 1}, 1}, {0.3, 0.6, {1, 1, 0}, 0.2}, {0.9, 0.9, {1, 1, 1}, 1}};
    std::printf("| TF size | compile ms | CG iterations (4 channels) | relative residual |\n|---|---|---|---|\n");
    for (int n : {64, 128, 256, 512}) {
        TfCompileStats stats;
        const auto t0 = std::chrono::steady_clock::now();
        compileTfLayers({base, ramp, spots}, n, n, &stats);
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        std::printf("| %d² | %.1f | %d | %.1e |\n", n, ms, stats.diffusionIterations, stats.worstResidual);
        std::fflush(stdout);
    }
    return 0;
}

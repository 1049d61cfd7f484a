// bench/stylizer_authoring: what issue #15's authoring costs per frame on the built-in forest
// (shadow map 2048², accelerated V̄): the homogeneous medium against the heterogeneous one (the
// built-in cloud's 64³ σt over the grove, 64–256 steps per view ray), its first frame (the
// optical-depth grid toward the light) apart; a compiled TF of layers; anchored constraints (the
// frame without the TF, the anchors found in its AOVs, the TF compiled and applied on the CPU);
// and a key-framed path midway between two keys. Medians of --reps frames (default 3).
// Usage: stylizer_authoring_bench [--reps N] [--size 640x360|1280x720|1920x1080]
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench_util.h"
#include "core/gpu/gpu_device.h"
#include "core/stylize/keyframes.h"
#include "core/stylize/stylizer.h"
#include "core/render/gpu_volume.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// Median total ms over `reps` frames after a first one (kernels compiled, caches warm).
double frameMs(Stylizer& stylizer, const StylizerScene& scene, int reps, double* firstMs = nullptr, GpuVolume* medium = nullptr) {
    StylizeSettings settings;
    settings.readShadowMaps = false;
    const StylizedFrame first = stylizer.render(scene, settings, medium);
    if (firstMs) *firstMs = first.totalMs;
    std::vector<double> ms;
    for (int r = 0; r < reps; ++r) ms.push_back(stylizer.render(scene, settings, medium).totalMs);
    return bench::median(ms);
}

TransferFunction layeredTf() {
    TransferFunction tf;
    tf.depthFar = 40;
    TfLayer base;
    base.solid = {0, 0, {1, 1, 1}, 1};
    TfLayer spots;
    spots.kind = TfLayerKind::Diffusion;
    spots.blend = TfBlend::Multiply;
    spots.constraints = {{0.9, 0.2, {1, 0.8, 0.5}, 1}, {0.1, 0.8, {0.4, 0.5, 1}, 1}, {0.5, 0.5, {1, 0.5, 0.3}, 1}};
    tf.layers = {base, spots};
    return tf;
}

}  // namespace

int main(int argc, char** argv) {
    spdlog::set_level(spdlog::level::warn);
    int reps = 3, width = 1920, height = 1080;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--size") && i + 1 < argc) std::sscanf(argv[++i], "%dx%d", &width, &height);
    }
    auto device = GpuDevice::create();
    Stylizer stylizer(*device);
    StylizerScene forest = builtinForest();
    forest.camera.width = width, forest.camera.height = height;
    forest.light.shadowMapSize = 2048;
    std::printf("stylizer authoring, builtin:forest %dx%d, shadow map 2048², accelerated V̄, medians of %d frames\n\n", width, height, reps);
    std::printf("| frame | ms | vs homogeneous |\n|---|---|---|\n");
    frameMs(stylizer, forest, 1);  // the process's first frames run slower (kernels, allocations)
    const double homogeneous = frameMs(stylizer, forest, reps);
    std::printf("| homogeneous medium | %.0f | 1.00× |\n", homogeneous);
    std::fflush(stdout);

    const Volume cloud = makeBuiltinScene("cloud", 64);
    for (int steps : {64, 128, 256}) {
        StylizerScene s = forest;
        GpuVolume medium(cloud);  // a fresh copy: the first frame builds its occupancy and T_l
        StylizerVolume v;
        v.lo = {-8, 0, -10}, v.hi = {8, 9, 6};
        v.extinctionScale = 0.02;
        v.steps = steps;
        s.volume = v;
        double first = 0;
        const double ms = frameMs(stylizer, s, reps, &first, &medium);
        std::printf("| heterogeneous, cloud 64³, %d steps (first frame: %.0f ms, with T_l) | %.0f | %.2f× |\n", steps, first, ms, ms / homogeneous);
        std::fflush(stdout);
    }

    StylizerScene layered = forest;
    layered.transferFunction = layeredTf();
    const double layeredMs = frameMs(stylizer, layered, reps);
    std::printf("| TF of 2 layers (128², compiled per frame here; the server compiles once) | %.0f | %.2f× |\n", layeredMs,
                layeredMs / homogeneous);
    StylizerScene anchored = layered;
    anchored.transferFunction->layers[1].constraints[0].anchor = TfAnchor{{-0.5, 3.2, -2}, ""};
    const double anchoredMs = frameMs(stylizer, anchored, reps);
    std::printf("| anchored constraint (TF applied on the CPU) | %.0f | %.2f× |\n", anchoredMs, anchoredMs / homogeneous);
    StylizerScene path = layered;
    StylizerKeyframe k0{0, forest.camera, layeredTf()}, k1{2, forest.camera, layeredTf()};
    k1.camera.eye = k1.camera.eye + Vec3d(2, 0.5, -1);
    k1.transferFunction->layers[1].constraints[0].colour = {0.3, 1, 0.4};
    path.keyframes = {k0, k1};
    const double pathMs = frameMs(stylizer, sceneAtTime(path, 1), reps);
    std::printf("| key-framed path midway (two TFs compiled and blended) | %.0f | %.2f× |\n", pathMs, pathMs / homogeneous);
    return 0;
}

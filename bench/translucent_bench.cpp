// bench/translucent: the translucent preview against single scattering (issue #14, SPEC §9):
// frame times at 480² and 1024² for the cloud at 64³–256³, with and without indirect light (the
// paper reports 50–60% overhead for its indirect term), and time against error for the slice
// spacing (against the ray marcher, indirect off, isotropic). `--quick`: 480² and 64³–128³ only.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench_util.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/translucent/translucent_renderer.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// One sun from behind and above, as docs/examples/translucent/backlit.json.
Lighting backlit() {
    Lighting l;
    l.lights = {{{0.25, 0.3, -1.0}, {30, 28, 25}}};
    l.background.color = {0.05, 0.06, 0.09};
    l.phase = {PhaseType::HenyeyGreenstein, 0.3};
    return l;
}

Camera front(int size) {
    Camera c;
    c.eye = {0, 0.15, 3.2};
    c.target = {0, -0.05, 0};
    c.fovYDeg = 36;
    c.width = c.height = size;
    return c;
}

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
    auto device = GpuDevice::create();
    Renderer marcher(*device);
    TranslucentRenderer slicer(*device);
    const Lighting light = backlit();

    std::printf("Frame time (ms, median of 3 after a warm-up), the cloud lit from behind, slices 1 voxel apart\n");
    std::printf("| image | volume | single scattering | translucent, direct only | translucent, indirect | indirect overhead | slices |\n|---|---|---|---|---|---|---|\n");
    for (int size : quick ? std::vector<int>{480} : std::vector<int>{480, 1024})
        for (int res : quick ? std::vector<int>{64, 128} : std::vector<int>{64, 128, 256}) {
            GpuVolume gpu(makeBuiltinScene("cloud", res));
            const Camera cam = front(size);
            auto time = [&](auto&& frame) {
                frame();
                std::vector<double> ms;
                for (int i = 0; i < 3; ++i) ms.push_back(frame());
                return bench::median(ms);
            };
            const double single = time([&] {
                RenderStats s;
                marcher.render(gpu, cam, light, {}, &s);
                return s.totalMs;
            });
            TranslucentSettings direct, indirect;
            direct.indirect.enabled = false;
            int slices = 0;
            auto sliced = [&](const TranslucentSettings& s) {
                return time([&] {
                    TranslucentStats st;
                    slicer.render(gpu, cam, light, s, &st);
                    slices = st.slices;
                    return st.totalMs;
                });
            };
            const double d = sliced(direct), i = sliced(indirect);
            std::printf("| %d² | %d³ | %.0f | %.0f | %.0f | %+.0f%% | %d |\n", size, res, single, d, i, 100 * (i / d - 1), slices);
            std::fflush(stdout);
        }

    std::printf("\nTime against error (64³ cloud, 480², isotropic, indirect off, against the ray marcher at 0.25 voxels)\n");
    std::printf("| slice spacing (voxels) | slices | ms | relative RMS |\n|---|---|---|---|\n");
    GpuVolume gpu(makeBuiltinScene("cloud", 64));
    Lighting iso = light;
    iso.phase = {PhaseType::Isotropic, 0};
    RenderSettings exact;
    exact.stepVoxels = 0.25;
    exact.terminationThreshold = 0;
    const Camera cam = front(480);
    const Image reference = marcher.render(gpu, cam, iso, exact);
    for (double spacing : {4.0, 2.0, 1.0, 0.5, 0.25}) {
        TranslucentSettings s;
        s.indirect.enabled = false;
        s.sliceSpacing = spacing;
        TranslucentStats st;
        const Image img = slicer.render(gpu, cam, iso, s, &st);
        std::printf("| %.2f | %d | %.0f | %.4f |\n", spacing, st.slices, st.totalMs, bench::relativeRms(img, reference));
        std::fflush(stdout);
    }
    return 0;
}

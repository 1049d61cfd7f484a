// Sparse volumes at production size (issue #39): memory and time against active voxels.
//
//   sparse_volume_bench                 the table: 256³–1024³ boxes at 1%, 5% and 20% active
//   sparse_volume_bench --plume FILE    a Houdini-sized sim (tests/tools/make_plume_vdb: 1024×512×1024,
//                                       density, temperature, vel): reads it, renders two views,
//                                       writes it back and checks the round trip
//
// Each step prints its wall time and the process's peak RSS so far (getrusage), next to what the
// dense equivalent would take. llvmpipe keeps textures in host memory, so the RSS includes the GPU's
// copy here.
#include <spdlog/spdlog.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "bench_util.h"
#include "core/gpu/gpu_device.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/solve/solver.h"
#include "core/stylize/medium_gpu.h"
#include "core/stylize/stylizer.h"
#include "core/volume/noise.h"
#include "core/volume/vdb_io.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

double peakRssMiB() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;
}

/// A box of n voxels a side with about `fraction` of its bricks active: coherent clumps where a
/// low-frequency noise is over a threshold found by bisection, and a smooth density inside them.
Volume clumpyVolume(int n, double fraction) {
    const PerlinNoise noise(7);
    const int b = (n + kBrickSide - 1) / kBrickSide;
    std::vector<double> field(size_t(b) * b * b);
    for (int z = 0, i = 0; z < b; ++z)
        for (int y = 0; y < b; ++y)
            for (int x = 0; x < b; ++x, ++i) field[size_t(i)] = noise.fbm(Vec3d(x, y, z) * (6.0 / b), 3);
    std::vector<double> sorted = field;
    std::sort(sorted.begin(), sorted.end());
    const double threshold = sorted[size_t((1.0 - fraction) * double(sorted.size() - 1))];
    BrickLayout layout(Int3{n, n, n}, Int3{0, 0, 0});
    for (int z = 0, i = 0; z < b; ++z)
        for (int y = 0; y < b; ++y)
            for (int x = 0; x < b; ++x, ++i)
                if (field[size_t(i)] > threshold) layout.activate({x, y, z});
    Volume v(std::move(layout), Mat4::translate(Vec3d(-1.0 + 1.0 / n)) * Mat4::scale(Vec3d(2.0 / n)));
    std::vector<float>& e = v.extinction();
    const double sigma = 4.0;  // per world unit: ~8 optical depths across the 2-unit box if it were full
    forEachActiveVoxel(v, [&](Int3 p, size_t s) {
        const float d = float(sigma * (0.6 + 0.4 * std::sin(0.11 * p.x) * std::cos(0.07 * p.y + 0.05 * p.z)));
        e[3 * s] = e[3 * s + 1] = e[3 * s + 2] = d;
    });
    return v;
}

Camera benchCamera(const Volume& v, int side) {
    Camera c = framingCamera(v.worldBounds());
    c.width = c.height = side;
    return c;
}

void table(GpuDevice& device, Renderer& renderer) {
    std::printf("| box | active voxels | host MiB (dense MiB) | GPU MiB | build ms | upload ms | first render ms | next render ms | "
                "emission solve: unknowns, ms (5 iterations, 2 × 128²) | peak RSS MiB |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    Lighting sun;
    sun.lights[0].direction = {0.4, 0.8, 0.3};
    for (int n : {256, 512, 1024}) {
        for (double fraction : {0.01, 0.05, 0.20}) {
            if (n == 1024 && fraction > 0.05) {
                std::printf("| %d³ | 20%% | (215 M active voxels: 2.5 GiB a grid twice over, and minutes a render on llvmpipe: on a GPU) |||||||\n", n);
                continue;
            }
            auto t0 = Clock::now();
            const Volume v = clumpyVolume(n, fraction);
            const double buildMs = msSince(t0);
            t0 = Clock::now();
            GpuVolume gpu(v);
            const double uploadMs = msSince(t0);
            const Camera cam = benchCamera(v, 256);
            t0 = Clock::now();
            renderer.render(gpu, cam, sun);
            const double firstMs = msSince(t0);
            t0 = Clock::now();
            const Image picture = renderer.render(gpu, cam, sun);
            const double nextMs = msSince(t0);
            // An emission solve toward the picture brightened by a quarter, from it and a side view.
            std::vector<SolveView> views;
            for (int i = 0; i < 2; ++i) {
                Camera c = benchCamera(v, 128);
                if (i == 1) c.eye = c.target + Vec3d(c.eye.z - c.target.z, c.eye.y - c.target.y, c.target.x - c.eye.x);
                Image target = renderer.render(gpu, c, sun);
                for (size_t p = 0; p < target.pixelCount(); ++p)
                    for (int ch = 0; ch < 3; ++ch) target.rgba[4 * p + size_t(ch)] *= 1.25f;
                views.push_back({"v" + std::to_string(i), c, target, std::nullopt});
            }
            SolveOptions opt;
            opt.maxIterations = 5;
            opt.analyzeReach = false;
            t0 = Clock::now();
            const SolveResult r = Solver(device, v, sun, views, opt).run();
            const double solveMs = msSince(t0);
            const double denseMiB = double(n) * n * n * 12 / (1 << 20);
            std::printf("| %d³ | %.1f%% (%zu) | %.0f (%.0f) | %.0f | %.0f | %.0f | %.0f | %.0f | %zu, %.0f | %.0f |\n", n,
                        100.0 * double(v.activeVoxels()) / (double(n) * n * n), v.activeVoxels(), double(v.memoryBytes()) / (1 << 20),
                        denseMiB, double(gpu.deviceBytes()) / (1 << 20), buildMs, uploadMs, firstMs, nextMs, r.report.unknownCount, solveMs,
                        peakRssMiB());
            std::fflush(stdout);
            device.cache().clear();  // the next box starts cold
        }
    }
}

/// The plume as the stylizer's heterogeneous medium over the built-in forest (960×540): the first
/// frame builds the block-mean medium and its light pass, the next reuses them.
void stylize(GpuDevice& device, GpuVolume& gpu) {
    StylizerScene scene = builtinForest();
    scene.camera.width = 960, scene.camera.height = 540;
    StylizerVolume medium;
    medium.lo = {-14, 0, -16}, medium.hi = {14, 14, 12};  // the plume's 2:1:2 box over the grove
    medium.extinctionScale = 0.5;
    scene.volume = medium;
    const int block = stylizerMediumBlock(gpu.dims(), medium.maxSparseMediumVoxels);
    Stylizer stylizer(device);
    for (int frame = 0; frame < 2; ++frame) {
        const auto t0 = Clock::now();
        const StylizedFrame f = stylizer.render(scene, {}, &gpu);
        std::printf("stylizer frame %d (960x540, the plume as its medium, blocks of %d³ voxels): %.1f s (shading, the medium's build included, %.1f s), peak RSS %.0f MiB\n",
                    frame, block, msSince(t0) / 1000, f.shadeMs / 1000, peakRssMiB());
    }
}

void plume(GpuDevice& device, Renderer& renderer, const std::string& path) {
    const std::string dir = std::filesystem::path(path).parent_path().string(), back = dir + "/plume_written.vdb";
    std::printf("%s: %.0f MiB\n", path.c_str(), double(std::filesystem::file_size(path)) / (1 << 20));
    auto t0 = Clock::now();
    const Volume v = loadVdb(path);
    const double denseGiB = double(v.dims().volume()) * 12 / (1 << 30);
    std::printf("read: %dx%dx%d box, %s, %zu active voxels (%.2f%%) in %zu bricks, %.0f MiB (dense: %.1f GiB a grid); %.1f s, peak RSS %.0f MiB\n",
                v.dims().x, v.dims().y, v.dims().z, v.isSparse() ? "sparse" : "dense", v.activeVoxels(),
                100.0 * double(v.activeVoxels()) / double(v.dims().volume()), v.isSparse() ? v.bricks()->activeBricks() : 0,
                double(v.memoryBytes()) / (1 << 20), denseGiB, msSince(t0) / 1000, peakRssMiB());
    t0 = Clock::now();
    GpuVolume gpu(v);
    std::printf("upload: %.0f MiB on the GPU, %.1f s, peak RSS %.0f MiB\n", double(gpu.deviceBytes()) / (1 << 20), msSince(t0) / 1000,
                peakRssMiB());
    Lighting sun;
    sun.lights[0].direction = {0.3, 0.9, 0.2};
    sun.lights[0].irradiance = Vec3d(3.0);
    std::vector<SolveView> views;
    for (int view = 0; view < 2; ++view) {
        Camera cam = framingCamera(v.worldBounds());
        if (view == 1) {  // a second view from the side
            const Vec3d toEye = cam.eye - cam.target;
            cam.eye = cam.target + Vec3d(toEye.z, toEye.y, -toEye.x);
        }
        cam.width = 480, cam.height = 270;
        t0 = Clock::now();
        RenderStats stats;
        const Image img = renderer.render(gpu, cam, sun, {}, &stats);
        double covered = 0;  // pixels the plume dims by more than 1%
        for (size_t i = 0; i < img.pixelCount(); ++i) covered += img.rgba[4 * i + 3] > 0.01f ? 1.0 / double(img.pixelCount()) : 0.0;
        std::printf("render view %d (480x270): %.1f s (light volume %.1f s), the plume covers %.1f%% of the frame, peak RSS %.0f MiB\n", view,
                    msSince(t0) / 1000, stats.lightMs / 1000, 100 * covered, peakRssMiB());
        saveImage(dir + "/plume_view" + std::to_string(view) + ".png", img);
        Image target = img;  // painted: a quarter brighter
        for (size_t p = 0; p < target.pixelCount(); ++p)
            for (int ch = 0; ch < 3; ++ch) target.rgba[4 * p + size_t(ch)] = 1 - (1 - target.rgba[4 * p + size_t(ch)]) * 0.8f;
        views.push_back({"v" + std::to_string(view), cam, target, std::nullopt});
    }
    SolveOptions opt;
    opt.maxIterations = 10;
    t0 = Clock::now();
    const SolveResult r = Solver(device, v, sun, views, opt).run();
    std::printf("solve: emission, %zu unknowns (%zu in the hull), %d iterations, RMS %.4f -> %.4f, %.1f s (forward %.1f, back-projection %.1f, "
                "vectors %.1f), peak RSS %.0f MiB\n",
                r.report.unknownCount, r.report.hullCount, r.report.iterations, r.report.initialRms[0], r.report.finalRms[0], msSince(t0) / 1000,
                r.report.forwardMs / 1000, r.report.adjointMs / 1000, r.report.vectorMs / 1000, peakRssMiB());
    stylize(device, gpu);
    t0 = Clock::now();
    saveVdb(back, r.volume);
    const auto diff = vdbDifferences(path, back);
    std::printf("write the solved volume: %.1f s, %zu differences from the file read (temperature and vel kept as they were), peak RSS %.0f MiB\n", msSince(t0) / 1000,
                diff.size(), peakRssMiB());
    for (const auto& line : diff) std::printf("  %s\n", line.c_str());
}

}  // namespace

int main(int argc, char** argv) {
    spdlog::set_level(spdlog::level::warn);
    auto device = GpuDevice::create();
    Renderer renderer(*device);
    if (argc == 3 && std::strcmp(argv[1], "--plume") == 0) {
        plume(*device, renderer, argv[2]);
    } else {
        table(*device, renderer);
    }
    std::printf("peak RSS %.0f MiB\n", peakRssMiB());
    return 0;
}

// Writes docs/examples/solve/: two "painted" target views of the built-in cloud (64³) with a warm
// glow in its core, as an artist might paint them, and the VIEWS.json that points at them. The
// views file carries a dimmer sun than the default so no pixel clips at 1 in the 16-bit PNGs
// (a clipped target asks for less light than the sun alone gives, which no emission can do).
// Regenerate with: build/bin/make_solve_example docs/examples/solve
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "core/gpu/gpu_device.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/volume/builtin_scenes.h"

using namespace volstyle;
using namespace volstyle::core;

int main(int argc, char** argv) {
    const std::filesystem::path dir = argc > 1 ? argv[1] : "docs/examples/solve";
    std::filesystem::create_directories(dir);
    Volume cloud = makeBuiltinScene("cloud", 64);
    auto& e = cloud.ensureEmission();
    for (int k = 0; k < 64; ++k)
        for (int j = 0; j < 64; ++j)
            for (int i = 0; i < 64; ++i) {
                Vec3d w = cloud.worldFromIndex().applyPoint({double(i), double(j), double(k)});
                double glow = std::exp(-std::pow(length(w - Vec3d(0.05, -0.25, 0.0)) / 0.35, 2));
                size_t n = 3 * cloud.index(i, j, k);
                e[n] = float(0.8 * glow), e[n + 1] = float(0.3 * glow), e[n + 2] = float(0.07 * glow);
            }
    auto device = GpuDevice::create();
    Renderer renderer(*device);
    GpuVolume gpu(cloud);
    Lighting lighting = defaultLighting();
    lighting.lights[0].irradiance = lighting.lights[0].irradiance * 0.45;
    const char* cams[2] = {R"({"eye": [0.0, 0.15, 3.4], "target": [0.0, -0.05, 0.0], "fov_y_deg": 38, "width": 96, "height": 96})",
                           R"({"eye": [3.2, 0.6, 1.0], "target": [0.0, -0.05, 0.0], "fov_y_deg": 38, "width": 96, "height": 96})"};
    Camera c0 = defaultCamera();
    c0.width = c0.height = 96;
    Camera c1 = c0;
    c1.eye = {3.2, 0.6, 1.0};
    int n = 0;
    for (const Camera& c : {c0, c1}) {
        Image img = renderer.render(gpu, c, lighting);
        SaveOptions opt;
        opt.bits = 16;
        saveImage((dir / ("painted" + std::to_string(++n) + ".png")).string(), img, opt);
    }
    std::ofstream(dir / "views.json") << "{\n  \"views\": [\n"
                                      << "    {\"name\": \"front\", \"camera\": " << cams[0] << ", \"target\": \"painted1.png\"},\n"
                                      << "    {\"name\": \"side\", \"camera\": " << cams[1] << ", \"target\": \"painted2.png\"}\n"
                                      << "  ],\n  \"lighting\": {\n"
                                      << "    \"lights\": [\n"
                                      << "      {\"direction\": [-0.55, 0.65, 0.55], \"irradiance\": [11.7, 11.025, 9.9]},\n"
                                      << "      {\"direction\": [0.0, 1.0, 0.0], \"irradiance\": [3.0, 4.0, 6.0]},\n"
                                      << "      {\"direction\": [0.2, -1.0, 0.1], \"irradiance\": [1.6, 1.5, 1.3]}\n"
                                      << "    ],\n"
                                      << "    \"background\": [0.32, 0.50, 0.82],\n"
                                      << "    \"phase\": {\"type\": \"henyey_greenstein\", \"g\": 0.25}\n  }\n}\n";
    std::cout << "wrote " << dir << "\n";
}

// `volstyle render`: one single-scattering image of a scene, to PNG (sRGB, exposure) or EXR
// (linear RGBA).

#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/base/errors.h"
#include "core/gpu/gpu_device.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "protocol/render_json.h"
#include "server/cli.h"
#include "server/scene_source.h"

namespace volstyle::server {
namespace {

namespace fs = std::filesystem;

const char* kUsage =
    "usage: volstyle render --scene builtin:NAME[:RES]|FILE.vdb [--camera CAM.json]\n"
    "                       [--lighting L.json] [--exposure STOPS] [--step VOXELS] [--no-skip]\n"
    "                       [--hw-filter] [--exact-traversal]\n"
    "                       -o OUT.png|OUT.exr\n";

}  // namespace

int runRender(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, {"scene", "camera", "lighting", "exposure", "step", "output"},
                                    {"no-skip", "hw-filter", "exact-traversal", "help"});
    if (args.has("help")) {
        std::cout << kUsage;
        return 0;
    }
    if (!args.has("scene")) throw InvalidArgument("--scene is required\n" + std::string(kUsage));
    if (!args.has("output")) throw InvalidArgument("-o OUT.png|OUT.exr is required");
    const std::string output = args.get("output");
    const std::string ext = fs::path(output).extension().string();
    if (ext != ".png" && ext != ".exr")
        throw InvalidArgument("-o must end in .png or .exr, got '" + output + "'");

    core::Camera camera = core::defaultCamera();
    if (args.has("camera")) camera = fromFile(args.get("camera"), [](const nlohmann::json& j) { return protocol::cameraFromJson(j); });
    core::Lighting lighting = core::defaultLighting();
    if (args.has("lighting")) {
        const std::string path = args.get("lighting");
        lighting = fromFile(path, [&](const nlohmann::json& j) { return lightingFromJsonFile(j, path); });
    }
    core::RenderSettings settings;
    settings.stepVoxels = args.number("step", settings.stepVoxels);
    settings.skipEmptySpace = !args.has("no-skip");
    settings.hardwareFilter = args.has("hw-filter");
    settings.exactTraversal = args.has("exact-traversal");
    settings.validate();
    const double exposure = args.number("exposure", 0);

    core::Volume volume = loadScene(args.get("scene"));
    auto device = core::GpuDevice::create();
    core::GpuVolume gpuVolume(volume);
    core::Renderer renderer(*device);
    core::RenderStats stats;
    core::Image image = renderer.render(gpuVolume, camera, lighting, settings, &stats);
    spdlog::info("rendered {}x{} in {:.1f} ms on {} (light volumes {:.1f} ms)", camera.width, camera.height,
                 stats.totalMs, device->capabilities().renderer, stats.lightMs);

    if (fs::path(output).has_parent_path()) fs::create_directories(fs::path(output).parent_path());
    core::SaveOptions save;
    save.exposure = ext == ".png" ? exposure : 0;  // EXR stays linear, unscaled
    core::saveImage(output, image, save);
    return 0;
}

}  // namespace volstyle::server

// `volstyle render`: one image of a scene, single scattering or the translucent preview
// (--mode translucent), to PNG (sRGB, exposure) or EXR (linear RGBA).

#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/cpu_ref/reference_renderer.h"
#include "core/gpu/gpu_device.h"
#include "core/image/image_io.h"
#include "core/render/exr_layers.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/translucent/translucent_renderer.h"
#include "protocol/render_json.h"
#include "cli/cli.h"
#include "cli/scene_source.h"

namespace volstyle::cli {
namespace {

namespace fs = std::filesystem;

const CommandSpec kRender{
    "render",
    "render a volume to PNG or EXR",
    "--scene builtin:NAME[:RES]|FILE.vdb [options] -o OUT.png|OUT.exr",
    "Renders one image of a volume: single scattering, or with --mode translucent the translucent\n"
    "preview (half-angle slicing with indirect light, docs/TRANSLUCENT.md). PNG is sRGB with\n"
    "--exposure applied; EXR is linear, premultiplied RGBA without the background, plus layers for\n"
    "the background and the AOVs (docs/FORMATS.md; translucent: the picture as layer 'beauty').\n"
    "Without --camera the camera frames the volume's bounding box.",
    {
        {"scene", "SRC", "builtin:NAME[:RES] (cloud, plume, sphere, cube; RES 8-256, default 128) or a .vdb file (required)"},
        {"camera", "CAM.json", "camera (eye, target, up, fov_y_deg, width, height); default: frames the volume, 480x480"},
        {"lighting", "L.json", "sun(s), background and phase function; default: one warm sun and a blue sky"},
        {"exposure", "STOPS", "PNG brightness in stops (EXR stays linear); default 0"},
        {"exr-type", "T", "EXR samples: half (default, pictures) or float (data: targets of a solve, CT)"},
        {"step", "VOXELS", "march step in voxels; default 0.5"},
        {"no-skip", "", "march through empty space too (a check; same image, slower)"},
        {"hw-filter", "", "sample with the texture unit (faster on GPUs, 8-bit weights)"},
        {"exact-traversal", "", "one segment per voxel crossed instead of equal steps"},
        {"reference", "", "the float64 CPU oracle with exact light integrals (slow: for checking accuracy; the picture only)"},
        {"glass", kGlassValue, kGlassHelp},
        {"no-refraction", "", "straight rays even through a refractive_index grid (default: rays bend, docs/REFRACTION.md)"},
        {"mode", "M", "single_scattering (default) or translucent"},
        {"translucent", "T.json", "translucent: its parameters as JSON (the API's \"translucent\" object); flags override"},
        {"slice-spacing", "VOXELS", "translucent: distance between slices; default 1"},
        {"blur-angle", "DEG", "translucent: the indirect light's cone angle, [0, 90); default 30"},
        {"indirect-extinction", "K", "translucent: indirect extinction per unit extinction; default 0.35"},
        {"transport", "R,G,B", "translucent: the transport colour, each in (0, 1]; default 1,0.78,0.55"},
        {"surface-shading", "S", "translucent: 0 attenuation only .. 1 Blinn-Phong from the gradient; default 0"},
        {"no-indirect", "", "translucent: direct light only"},
        {"perturb", "AMP[,FREQ]", "translucent: noise displacing the lookups by up to AMP voxels, FREQ features across (default 8)"},
        {"perturb-extinction", "A", "translucent: noise scaling the extinction by 1 +- A, [0, 1]; default 0"},
        {"seed", "N", "translucent: the perturbation's noise; default 1"},
        {"time", "T", "translucent: the perturbation's animation time; default 0"},
        {"output", "OUT", ".png or .exr; the folder must exist (required)"},
    },
    "  volstyle render --scene builtin:cloud:64 -o cloud.png\n"
    "  volstyle render --scene builtin:plume:48 --exposure 1 -o plume.exr\n"
    "  volstyle render --scene builtin:cloud:64 --mode translucent --transport 1,0.6,0.3 -o glow.png\n"
    "  volstyle render --scene builtin:cloud:64 --glass 1.33 -o through-glass.png\n"};

/// The translucent preview's parameters: T.json, then the flags; validated (InvalidArgument).
core::TranslucentSettings translucentSettings(const Arguments& args) {
    core::TranslucentSettings s;
    if (args.has("translucent"))
        s = fromFile(args.get("translucent"), [](const nlohmann::json& j) { return protocol::translucentFromJson(j); });
    if (args.has("slice-spacing")) s.sliceSpacing = args.number("slice-spacing", s.sliceSpacing);
    if (args.has("blur-angle")) s.indirect.blurAngleDeg = args.number("blur-angle", s.indirect.blurAngleDeg);
    if (args.has("indirect-extinction")) s.indirect.extinction = args.number("indirect-extinction", s.indirect.extinction);
    if (args.has("surface-shading")) s.surfaceShading = args.number("surface-shading", s.surfaceShading);
    if (args.has("no-indirect")) s.indirect.enabled = false;
    if (args.has("perturb")) {
        const auto parts = split(args.get("perturb"), ',');
        if (parts.empty() || parts.size() > 2) throw InvalidArgument("--perturb takes AMP or AMP,FREQ, got '" + args.get("perturb") + "'");
        s.perturbation.amplitude = parseNumber("perturb", parts[0]);
        if (parts.size() == 2) s.perturbation.frequency = parseNumber("perturb", parts[1]);
    }
    if (args.has("perturb-extinction")) s.perturbation.propertyAmplitude = args.number("perturb-extinction", 0);
    if (args.has("seed")) s.perturbation.seed = uint32_t(args.number("seed", 1));
    if (args.has("time")) s.perturbation.time = args.number("time", 0);
    if (args.has("transport")) {
        const std::vector<double> rgb = numbers("transport", args.get("transport"), 3);
        s.indirect.transportColor = {rgb[0], rgb[1], rgb[2]};
    }
    s.validate();
    return s;
}

}  // namespace

const CommandSpec& renderCommand() { return kRender; }

namespace {

/// The march settings of --step, --no-skip, --hw-filter, --exact-traversal and --no-refraction.
core::RenderSettings renderSettings(const Arguments& args) {
    core::RenderSettings settings;
    settings.stepVoxels = args.number("step", settings.stepVoxels);
    settings.skipEmptySpace = !args.has("no-skip");
    settings.hardwareFilter = args.has("hw-filter");
    settings.exactTraversal = args.has("exact-traversal");
    settings.refraction = !args.has("no-refraction");
    settings.validate();
    return settings;
}

/// --mode: true for translucent; the flags of the other mode refused.
bool translucentMode(const Arguments& args) {
    const std::string mode = args.has("mode") ? args.get("mode") : "single_scattering";
    if (mode != "single_scattering" && mode != "translucent")
        throw InvalidArgument("--mode must be single_scattering or translucent, got '" + mode + "'");
    const bool translucent = mode == "translucent";
    if (translucent && (args.has("glass") || args.has("no-refraction")))
        throw InvalidArgument("--glass and --no-refraction are for single scattering: the translucent preview's rays are straight");
    for (const char* flag : {"translucent", "slice-spacing", "blur-angle", "indirect-extinction", "transport", "surface-shading", "no-indirect",
                             "perturb", "perturb-extinction", "seed", "time"})
        if (!translucent && args.has(flag)) throw InvalidArgument(std::string("--") + flag + " needs --mode translucent");
    return translucent;
}

/// How -o is written: EXR (half or float, --exr-type) with layers, or a picture with --exposure.
struct Output {
    std::string path;
    bool exr = false, exrHalf = true;
    core::SaveOptions picture;
};

Output outputOf(const Arguments& args) {
    Output out;
    out.path = imageOutputPath(args);
    out.exr = fs::path(out.path).extension() == ".exr";
    const std::string exrType = args.has("exr-type") ? args.get("exr-type") : "half";
    if (exrType != "half" && exrType != "float") throw InvalidArgument("--exr-type must be half or float, got '" + exrType + "'");
    if (args.has("exr-type") && !out.exr) throw InvalidArgument("--exr-type is for -o OUT.exr");
    out.exrHalf = exrType == "half";
    out.picture.exposure = args.number("exposure", 0);
    return out;
}

void renderTranslucent(core::GpuDevice& device, core::GpuVolume& volume, const core::Camera& camera, const core::Lighting& lighting,
                       const core::TranslucentSettings& options, const Output& output) {
    core::TranslucentRenderer preview(device);
    core::TranslucentStats stats;
    core::Image medium;
    const core::Image image = preview.render(volume, camera, lighting, options, &stats, &medium);
    if (output.exr) core::saveExrLayers(output.path, {{"", &medium}, {"beauty", &image}}, output.exrHalf);
    else core::saveImage(output.path, image, output.picture);
    spdlog::info("rendered {}x{} translucent, {} slices, in {:.1f} ms on {}", camera.width, camera.height, stats.slices, stats.totalMs,
                 device.capabilities().renderer);
}

void renderSingleScattering(core::GpuDevice& device, core::GpuVolume& volume, const core::Camera& camera, const core::Lighting& lighting,
                            const core::RenderSettings& settings, const Output& output) {
    const auto t0 = Clock::now();
    core::Renderer renderer(device);
    core::RenderStats stats;
    if (output.exr) {
        // Compositing-ready: premultiplied medium without the background, plus its layers.
        const core::RenderLayers layers = renderer.renderLayers(volume, camera, lighting, settings, &stats);
        core::saveExrLayers(output.path, core::exrLayersOf(layers), output.exrHalf);
    } else {
        core::saveImage(output.path, renderer.render(volume, camera, lighting, settings, &stats), output.picture);
    }
    spdlog::info("rendered {}x{} in {:.1f} ms on {} (light volumes {:.1f} ms, occupancy {:.1f} ms); written in {:.1f} ms", camera.width,
                 camera.height, stats.totalMs, device.capabilities().renderer, stats.lightMs, stats.occupancyMs, msSince(t0) - stats.totalMs);
}

}  // namespace

int runRender(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, kRender);
    if (printHelpIfAsked(args, kRender)) return 0;
    if (!args.has("scene")) throw InvalidArgument("--scene is required (volstyle render --help)");
    const Output output = outputOf(args);
    std::optional<core::Camera> camera;
    if (args.has("camera")) camera = fromFile(args.get("camera"), [](const nlohmann::json& j) { return protocol::cameraFromJson(j); });
    core::Lighting lighting = core::defaultLighting();
    if (args.has("lighting")) {
        const std::string path = args.get("lighting");
        lighting = fromFile(path, [&](const nlohmann::json& j) { return lightingFromJsonFile(j, path); });
    }
    const core::RenderSettings settings = renderSettings(args);
    const bool translucent = translucentMode(args);
    const core::TranslucentSettings translucentOptions = translucent ? translucentSettings(args) : core::TranslucentSettings{};

    auto t0 = Clock::now();
    core::Volume volume = loadScene(args.get("scene"));
    applyGlassOption(args, volume);
    if (!camera) camera = core::framingCamera(volume.worldBounds());
    spdlog::debug("scene {} loaded in {:.1f} ms", args.get("scene"), msSince(t0));
    if (args.has("reference")) {  // no GL: every light integral marched from the sample itself
        if (translucent) throw InvalidArgument("--reference renders single scattering; leave out --mode translucent");
        t0 = Clock::now();
        const core::Image image = core::cpu_ref::renderReference<double>(volume, *camera, lighting, settings.stepVoxels,
                                                                         core::cpu_ref::LightDepthMethod::Exact, settings.stepVoxels / 4);
        core::saveImage(output.path, image, output.picture);
        spdlog::info("rendered {}x{} with the float64 reference in {:.1f} s", camera->width, camera->height, msSince(t0) / 1000);
        return 0;
    }
    t0 = Clock::now();
    auto device = core::GpuDevice::create();
    core::GpuVolume gpuVolume(volume);
    spdlog::debug("GL device created and volume uploaded in {:.1f} ms", msSince(t0));
    if (translucent) renderTranslucent(*device, gpuVolume, *camera, lighting, translucentOptions, output);
    else renderSingleScattering(*device, gpuVolume, *camera, lighting, settings, output);
    return 0;
}

}  // namespace volstyle::cli

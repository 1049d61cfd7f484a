// `volstyle stylize`: one frame of the light-shaft stylizer (SPEC §7) to PNG or EXR, or one of its
// AOVs: a directional or spot light, naive or accelerated V̄, the occluders' manipulations and the
// transfer function.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <tuple>

#include "core/base/errors.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/image/image_io.h"
#include "core/stylize/keyframes.h"
#include "core/stylize/stylizer.h"
#include "core/stylize/stylizer_files.h"
#include "core/stylize/mesh_io.h"
#include "protocol/render_json.h"
#include "protocol/stylize_json.h"
#include "cli/cli.h"
#include "cli/scene_source.h"
#include "server/runtime/video_encoder.h"

namespace volstyle::cli {
namespace {

namespace fs = std::filesystem;

const CommandSpec kStylize{
    "stylize",
    "render light shafts through occluders (the stylizer)",
    "--scene SCENE.json|builtin:NAME [options] -o OUT.png|OUT.exr | --sequence FOLDER [--video OUT.mp4]",
    "Renders one frame of the light-shaft stylizer: occluder surfaces lit and shadowed by a\n"
    "directional or spot light, and single scattering in a homogeneous medium with the visibility along\n"
    "each view ray factored out (the average visibility V̄). --aov writes one of the frame's\n"
    "arbitrary output variables instead of the frame. --sequence renders the scene's camera path (its\n"
    "key frames: camera and transfer function interpolated linearly) as PNG frames, and --video encodes\n"
    "them with ffmpeg.",
    {
        {"scene", "SRC", "SCENE.json (docs/STYLIZER.md; mesh paths relative to it, or builtin:forest/ground|trees) or builtin:forest (required)"},
        {"camera", "CAM.json", "camera (eye, target, up, fov_y_deg, width, height); default: the scene's (builtin:forest: 640x360; a file without one: 480x480)"},
        {"aov", "NAME", "average_visibility, linear_depth, shadow_map, modified_shadow_map or scattering; default: the frame"},
        {"method", "NAME", "how V̄ is computed: accelerated (exact, min-max mipmap) or naive (--steps lookups per ray); default accelerated"},
        {"steps", "N", "shadow-map lookups per view ray for the naive V̄ (1-4096); default 256"},
        {"time", "T", "scene time for animated holes; default: the scene's (0)"},
        {"exposure", "STOPS", "PNG brightness in stops (EXR stays linear); default 0"},
        {"output", "OUT", ".png or .exr; the folder must exist (required without --sequence)"},
        {"sequence", "FOLDER", "render a sequence into FOLDER/frame_00000.png, … (created); default: one frame"},
        {"fps", "N", "sequence frames per second of scene time (0-240]; default 24"},
        {"start", "T", "sequence start time; default: the first key frame's (no keys: the scene's time)"},
        {"end", "T", "sequence end time; default: the last key frame's (required without keys)"},
        {"video", "OUT.mp4", "also encode the sequence as H.264 MP4 with ffmpeg; default: frames only"},
    },
    "  volstyle stylize --scene builtin:forest -o forest.png\n"
    "  volstyle stylize --scene builtin:forest --aov average_visibility -o vbar.png\n"
    "  volstyle stylize --scene builtin:forest --method naive --steps 1024 -o reference.exr\n"
    "  volstyle stylize --scene docs/examples/stylize/window.json -o window.png\n"
    "  volstyle stylize --scene docs/examples/stylize/path.json --sequence out/path --video out/path.mp4\n"};

/// builtin:forest, or a SCENE.json whose mesh paths are relative to it.
/// The scene file `spec`, and in `medium` the volume its /volume/source names (if any).
core::StylizerScene loadStylizerScene(const std::string& spec, std::optional<core::Volume>& medium) {
    if (spec == "builtin:forest") return core::builtinForest();
    if (spec.rfind("builtin:", 0) == 0) throw InvalidArgument("--scene: unknown scene '" + spec + "' (built-in: builtin:forest)");
    protocol::StylizerSceneRequest request =
        fromFile(spec, [](const nlohmann::json& j) { return protocol::stylizerSceneFromJson(j); });
    const fs::path folder = fs::path(spec).parent_path();
    for (size_t i = 0; i < request.meshRefs.size(); ++i) {
        const std::string where = "'" + spec + "': /occluders/" + std::to_string(i) + "/mesh: ";
        if (auto builtin = protocol::builtinMesh(request.meshRefs[i])) {  // builtin:forest/NAME, as in the API
            request.scene.occluders[i].mesh = builtin;
            continue;
        }
        try {
            request.scene.occluders[i].mesh = std::make_shared<const core::Mesh>(core::loadMesh((folder / request.meshRefs[i]).string()));
        } catch (const IoError& e) {
            throw IoError(where + e.what());
        } catch (const InvalidArgument& e) {
            throw InvalidArgument(where + e.what());
        }
    }
    for (const protocol::TfImageRef& ref : request.tfImages) {
        const std::string path = (folder / ref.ref).string();
        try {
            protocol::attachTfImage(request.scene, ref, std::make_shared<core::Image>(core::loadImage(path, 4096).image));
        } catch (const Error& e) {
            throw InvalidArgument("'" + spec + "': " + (ref.key < 0 ? "" : "/keyframes/" + std::to_string(ref.key)) + "/transfer_function/" +
                                  (ref.layer < 0 ? "" : "layers/" + std::to_string(ref.layer) + "/") + "image: " + e.what());
        }
    }
    if (request.scene.volume) {  // a VDB path relative to the file, or builtin:NAME
        const std::string& source = request.volumeSource;
        const std::string where = source.rfind("builtin:", 0) == 0 ? source : (folder / source).string();
        core::Volume volume;
        try {
            volume = loadScene(where);
        } catch (const Error& e) {
            throw InvalidArgument("'" + spec + "': /volume/source: " + e.what());
        }
        if (!request.volumeBoxGiven) std::tie(request.scene.volume->lo, request.scene.volume->hi) = volume.worldBounds();
        medium = std::move(volume);
    }
    return request.scene;
}

}  // namespace

const CommandSpec& stylizeCommand() { return kStylize; }

namespace {

/// --sequence: every frame of the span into FOLDER (PNG), then the video when asked.
/// A sequence's frames at most (10 minutes at 24 fps).
constexpr size_t kMaxSequenceFrames = 14400;

int renderSequence(const Arguments& args, const core::StylizerScene& scene, const std::optional<core::Volume>& volume,
                   const core::StylizeSettings& settings, core::StylizerOutput output) {
    const fs::path folder = args.get("sequence");
    const double fps = args.number("fps", 24);
    const auto [first, last] = core::pathSpan(scene.keyframes);
    if (scene.keyframes.empty() && !args.has("end")) throw InvalidArgument("--end is required for a scene without key frames");
    const double start = args.number("start", scene.keyframes.empty() ? scene.time : first);
    const double end = args.number("end", last);
    std::vector<double> times;
    try {
        times = core::sequenceTimes(start, end, fps, kMaxSequenceFrames);
    } catch (const InvalidArgument& e) {
        throw InvalidArgument(std::string("--fps/--start/--end: ") + e.what());
    }
    core::checkPathCameras(scene, times);
    std::string video;
    if (args.has("video")) {
        video = args.get("video");
        if (fs::path(video).extension() != ".mp4") throw InvalidArgument("--video must end in .mp4, got '" + video + "'");
        requireParentFolder(video);
        if (server::findFfmpeg().empty()) throw InvalidArgument("--video needs ffmpeg on PATH (Debian: apt install ffmpeg)");
    }
    fs::create_directories(folder);
    auto device = core::GpuDevice::create();
    core::Stylizer stylizer(*device);
    std::optional<core::GpuVolume> medium;
    if (volume) medium.emplace(*volume);
    const core::SaveOptions save = core::stylizerSaveOptions(output, args.number("exposure", 0));
    for (size_t i = 0; i < times.size(); ++i) {
        const core::StylizedFrame f = stylizer.render(core::sceneAtTime(scene, times[i]), settings, medium ? &*medium : nullptr);
        core::saveImage((folder / server::sequenceFrameName(i)).string(), f.output(output), save);
        spdlog::info("frame {}/{} (t = {:.3f}) in {:.0f} ms", i + 1, times.size(), times[i], f.totalMs);
    }
    if (!video.empty()) {
        server::encodeVideo(folder, times.size(), fps, video);
        spdlog::info("encoded {} frames at {:g} fps into '{}'", times.size(), fps, video);
    }
    return 0;
}

}  // namespace

int runStylize(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, kStylize);
    if (printHelpIfAsked(args, kStylize)) return 0;
    if (!args.has("scene")) throw InvalidArgument("--scene is required (volstyle stylize --help)");
    const bool sequence = args.has("sequence");
    if (sequence && args.has("output")) throw InvalidArgument("-o and --sequence: a sequence is written to its folder; give one of them");
    for (const char* option : {"fps", "start", "end", "video"})
        if (!sequence && args.has(option)) throw InvalidArgument(std::string("--") + option + " belongs to --sequence");
    const std::string outputPath = sequence ? std::string() : imageOutputPath(args);
    const std::string method = args.has("method") ? args.get("method") : "accelerated";
    if (method != "naive" && method != "accelerated")
        throw InvalidArgument("--method: '" + method + "' is not one of accelerated, naive");
    const std::string aov = args.has("aov") ? args.get("aov") : "frame";
    const auto output = protocol::stylizerOutputFromName(aov);
    if (!output) throw InvalidArgument("--aov: '" + aov + "' is not one of " + protocol::kStylizerAovNames);

    std::optional<core::Volume> volume;
    core::StylizerScene scene = loadStylizerScene(args.get("scene"), volume);
    if (args.has("camera") && !scene.keyframes.empty())
        throw InvalidArgument("--camera: the scene's key frames set the camera (a camera path); leave --camera out");
    if (args.has("camera"))
        scene.camera = fromFile(args.get("camera"), [](const nlohmann::json& j) { return protocol::cameraFromJson(j); });
    if (args.has("time")) {
        scene.time = args.number("time", 0);
        if (!(std::abs(scene.time) <= 1e9)) throw InvalidArgument("--time: must be a finite number (|T| <= 1e9)");
    }
    core::StylizeSettings settings;
    settings.method = method == "naive" ? core::VisibilityMethod::Naive : core::VisibilityMethod::Accelerated;
    const double steps = args.number("steps", settings.steps);
    if (steps != std::floor(steps)) throw InvalidArgument("--steps: must be a whole number");
    settings.steps = int(std::clamp(steps, -1.0, 1e6));
    core::readBackOnly(settings, *output);
    settings.validate();

    if (sequence) return renderSequence(args, scene, volume, settings, *output);
    scene = core::sceneAtTime(scene, scene.time);  // on a path: its camera at the scene's time
    auto device = core::GpuDevice::create();
    core::Stylizer stylizer(*device);
    std::optional<core::GpuVolume> medium;
    if (volume) medium.emplace(*volume);
    const core::StylizedFrame f = stylizer.render(scene, settings, medium ? &*medium : nullptr);
    const core::SaveOptions save = core::stylizerSaveOptions(*output, args.number("exposure", 0));
    core::saveImage(outputPath, f.output(*output), save);
    spdlog::info("stylized {}x{} in {:.1f} ms (shadow maps and edits {:.1f}, min-max mipmap {:.1f}, G-buffer {:.1f}, shading {:.1f}, read back {:.1f})",
                 scene.camera.width, scene.camera.height, f.totalMs, f.shadowMs, f.mipmapMs, f.gbufferMs, f.shadeMs, f.readbackMs);
    return 0;
}

}  // namespace volstyle::cli

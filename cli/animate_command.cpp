// `volstyle animate`: an animated volume (a VDB per frame) restyled from painted key frames and/or
// rendered frame by frame (issue #16; core/solve/keyframe_solver.h).

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/gpu/gpu_device.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/solve/keyframe_solver.h"
#include "core/volume/sequence.h"
#include "core/volume/vdb_io.h"
#include "protocol/render_json.h"
#include "cli/cli.h"

namespace volstyle::cli {
namespace {

namespace fs = std::filesystem;

const CommandSpec kAnimate{
    "animate",
    "restyle or render an animated volume (a VDB per frame)",
    "--frames PATTERN --range A-B [--views VIEWS.json -o OUT_PATTERN.vdb] [--render OUT_PATTERN.png --camera CAM.json]",
    "Reads frames A..B of PATTERN (printf style: smoke.%04d.vdb), or of one VDB holding them all\n"
    "(grids named density.12, vel_12, or with a 'frame' metadata entry). With --views (each view names its\n"
    "\"frame\"), the frames that have views are key frames, solved jointly: each frame's views, plus\n"
    "a temporal term tying neighbouring key frames voxel for voxel or, where the files carry a `vel`\n"
    "grid, along the flow; the frames between key frames are blended from them (carried along the\n"
    "flow), those before the first or after the last carried from it. -o writes every frame's VDB.\n"
    "--render writes a PNG per frame (the solved frames, else the input), with progress.\n"
    "docs/ANIMATION.md has the method and the measurements.",
    {
        {"frames", "PATTERN", "the frames' VDB files, printf style (smoke.%04d.vdb), or one VDB whose grids are stamped with frames (required)"},
        {"range", "A-B", "the first and last frame numbers (required)"},
        {"views", "VIEWS.json", "painted views as for solve, each with \"frame\": N; default none (render only)"},
        {"unknowns", "U", "emission or albedo; default emission"},
        {"temporal", "W", "weight of the temporal term per unknown (as l2); default 0.05"},
        {"sweeps", "N", "Gauss-Seidel sweeps over the key frames, 1-100; default 3"},
        {"iterations", "N", "most CGLS iterations per key frame and sweep; default 30"},
        {"no-flow", "", "tie key frames voxel for voxel even where the files carry velocity"},
        {"storage", "MODE", "how frames are stored: auto (dense while the box fits 256^3 voxels), dense or sparse (8^3 bricks); default auto"},
        {"fps", "F", "frames per second, to turn the files' velocity (units per second) into units per frame; default 24"},
        {"camera", "CAM.json", "the camera of --render (eye, target, up, fov_y_deg, width, height); default: frames the first frame"},
        {"lighting", "L.json", "sun(s), background and phase function; default: one warm sun and a blue sky"},
        {"exposure", "STOPS", "PNG brightness in stops; default 0"},
        {"render", "OUT_PATTERN.png", "render every frame to PNG, printf style; default none"},
        {"quiet", "", "no progress lines"},
        {"output", "OUT_PATTERN.vdb", "write every frame's volume, printf style; needs --views (default none)"},
    },
    "  volstyle animate --frames smoke.%04d.vdb --range 1-48 --views keys.json -o styled.%04d.vdb\n"
    "  volstyle animate --frames styled.%04d.vdb --range 1-48 --camera cam.json --render frames/%04d.png\n"};

/// PATTERN with frame f (printf style, one integer conversion).
std::string frameName(const std::string& pattern, int f) {
    const size_t pct = pattern.find('%');
    if (pct == std::string::npos) throw InvalidArgument("'" + pattern + "' has no frame number (use %d or %04d)");
    size_t end = pct + 1;
    while (end < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[end]))) ++end;
    if (end >= pattern.size() || pattern[end] != 'd' || pattern.find('%', end) != std::string::npos)
        throw InvalidArgument("'" + pattern + "' must hold exactly one %d or %0Nd");
    char number[32];
    std::snprintf(number, sizeof number, ("%" + pattern.substr(pct + 1, end - pct)).c_str(), f);
    return pattern.substr(0, pct) + number + pattern.substr(end + 1);
}

std::pair<int, int> frameRange(const std::string& text) {
    const auto parts = split(text, '-');
    if (parts.size() != 2) throw InvalidArgument("--range takes A-B, got '" + text + "'");
    const double a = parseNumber("range", parts[0]), b = parseNumber("range", parts[1]);
    if (a != std::floor(a) || b != std::floor(b) || a < 0 || b < a || b - a > 100000)
        throw InvalidArgument("--range must be whole frame numbers A <= B, got '" + text + "'");
    return {int(a), int(b)};
}

void progressLine(bool quiet, const std::string& line) {
    if (!quiet) std::fprintf(stderr, "%s\n", line.c_str());
}

}  // namespace

const CommandSpec& animateCommand() { return kAnimate; }

namespace {

/// The frames first..last (a file each by a %d pattern, or one file holding them all) and their
/// velocity in world units per frame; with `oneGrid`, every frame must share the first's grid.
struct Frames {
    std::vector<core::Volume> volumes;
    std::vector<std::vector<float>> velocity;
};

Frames readFrames(const std::string& pattern, int first, int last, double fps, bool oneGrid, const core::VolumeLimits& limits) {
    std::map<int, core::Volume> stamped;
    const bool oneFile = pattern.find('%') == std::string::npos;
    if (oneFile) {
        stamped = core::loadVdbFrames(pattern, limits);
        if (stamped.empty())
            throw InvalidArgument("'" + pattern + "' has no frame number (use %d or %04d) and holds no grids stamped with a frame "
                                  "(density.12, vel_12, or a 'frame' metadata entry)");
    }
    Frames out;
    auto& frames = out.volumes;
    for (int f = first; f <= last; ++f) {
        if (oneFile && !stamped.count(f)) throw InvalidArgument("'" + pattern + "' holds no frame " + std::to_string(f));
        frames.push_back(oneFile ? std::move(stamped[f]) : core::loadVdb(frameName(pattern, f), limits));
        std::vector<float> v = core::velocityOf(frames.back());
        for (float& x : v) x = float(x / fps);
        out.velocity.push_back(std::move(v));
        if (oneGrid && (!(frames.back().dims() == frames[0].dims()) || !(frames.back().worldFromIndex() == frames[0].worldFromIndex())))
            throw InvalidArgument("frame " + std::to_string(f) + " does not share frame " + std::to_string(first) +
                                  "'s grid (dims and transform): resample the sequence onto one grid first");
    }
    return out;
}

/// Solves the key frames (the frames the views are on) and fills every frame from them; writes
/// them to -o when given.
void solveFrames(const Arguments& args, core::GpuDevice& device, Frames& in, std::vector<core::SolveView> views,
                 const std::vector<int>& viewFrames, const core::Lighting& lighting, int first, int last) {
    const bool quiet = args.has("quiet");
    const auto t0 = Clock::now();
    auto& frames = in.volumes;
    std::map<int, std::vector<core::SolveView>> byFrame;
    for (size_t i = 0; i < views.size(); ++i) byFrame[viewFrames[i]].push_back(std::move(views[i]));
    core::KeyFrameOptions o;
    o.solve.unknown = args.get("unknowns", "emission") == "emission" ? core::Unknown::Emission : core::Unknown::Albedo;
    o.solve.maxIterations = int(args.number("iterations", 30));
    o.temporal = args.number("temporal", 0.05);
    o.sweeps = int(args.number("sweeps", 3));
    o.followFlow = !args.has("no-flow");
    o.solve.validate();
    std::vector<core::Volume*> all;  // sparse frames: one layout, so values carry brick for brick
    for (core::Volume& frame : frames) all.push_back(&frame);
    core::putFramesOnOneLayout(all, {}, o.solve.unknown);
    if (frames[0].isSparse())  // the files' velocity over the whole layout, where it reaches past a frame's own bricks too
        for (size_t i = 0; i < frames.size(); ++i) {
            in.velocity[i] = core::velocityOf(frames[i]);
            for (float& x : in.velocity[i]) x = float(x / args.number("fps", 24));
        }
    std::vector<core::KeyFrame> keys;
    for (auto& [f, v] : byFrame) keys.push_back({f, frames[size_t(f - first)], std::move(v), in.velocity[size_t(f - first)]});
    core::KeyFrameReport report;
    const auto solved = core::solveKeyFrames(device, keys, lighting, o, &report, [&](int sweep, int k) {
        progressLine(quiet, "sweep " + std::to_string(sweep + 1) + "/" + std::to_string(o.sweeps) + ": key frame " +
                                std::to_string(keys[size_t(k)].frame));
    });
    // Every frame: a key frame's solution; between two, their blend; outside, the nearest carried.
    for (int f = first; f <= last; ++f) {
        core::Volume& frame = frames[size_t(f - first)];
        (o.solve.unknown == core::Unknown::Emission ? frame.ensureEmission() : frame.ensureAlbedo()) =
            core::frameFromKeys(keys, solved, o.solve.unknown, f, o.followFlow);
    }
    std::string changes;
    for (double c : report.change) changes += (changes.empty() ? "" : ", ") + std::to_string(c);
    progressLine(quiet, fmt::format("{} key frames solved in {:.1f} s ({:.1f} s solving, {:.1f} s extending into empty voxels); "
                                    "largest change per sweep: {}",
                                    keys.size(), msSince(t0) / 1000, report.solveSeconds, report.extendSeconds, changes));
    for (size_t k = 0; k < keys.size(); ++k) {
        std::string rms;
        for (size_t v = 0; v < report.frames[k].finalRms.size(); ++v)
            rms += fmt::format("{}{:.4g} -> {:.4g}", v ? ", " : "", report.startRms[k][v], report.frames[k].finalRms[v]);
        if (!rms.empty()) progressLine(quiet, fmt::format("key frame {}: RMS per view {}", keys[k].frame, rms));
    }
    if (args.has("output"))
        for (int f = first; f <= last; ++f) {
            core::saveVdb(frameName(args.get("output"), f), frames[size_t(f - first)]);
            progressLine(quiet, "wrote " + frameName(args.get("output"), f));
        }
}

/// Renders every frame to --render (one camera: --camera, or framing the first frame).
void renderFrames(const Arguments& args, core::GpuDevice& device, const std::vector<core::Volume>& frames, const core::Lighting& lighting,
                  int first, int last) {
    core::Camera camera = args.has("camera") ? fromFile(args.get("camera"), [](const nlohmann::json& j) { return protocol::cameraFromJson(j); })
                                             : core::framingCamera(frames[0].worldBounds());
    core::Renderer renderer(device);
    core::SaveOptions save;
    save.exposure = args.number("exposure", 0);
    for (int f = first; f <= last; ++f) {
        core::GpuVolume gpu(frames[size_t(f - first)]);
        core::saveImage(frameName(args.get("render"), f), renderer.render(gpu, camera, lighting), save);
        progressLine(args.has("quiet"), "frame " + std::to_string(f - first + 1) + "/" + std::to_string(last - first + 1) + ": " +
                                            frameName(args.get("render"), f));
    }
}

}  // namespace

int runAnimate(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, kAnimate);
    if (printHelpIfAsked(args, kAnimate)) return 0;
    for (const char* required : {"frames", "range"})
        if (!args.has(required)) throw InvalidArgument(std::string("--") + required + " is required (volstyle animate --help)");
    const auto [first, last] = frameRange(args.get("range"));
    const bool solve = args.has("views");
    if (args.has("output") && !solve) throw InvalidArgument("-o writes solved frames: it needs --views");
    if (!args.has("output") && !args.has("render")) throw InvalidArgument("nothing to do: give -o (with --views) or --render");
    const std::string unknownName = args.get("unknowns", "emission");
    if (unknownName != "emission" && unknownName != "albedo") throw InvalidArgument("--unknowns must be emission or albedo, got '" + unknownName + "'");
    const double fps = args.number("fps", 24);
    if (!(fps > 0 && fps <= 1000)) throw InvalidArgument("--fps must be in (0, 1000]");
    if (args.has("output")) requireParentFolder(frameName(args.get("output"), first));
    if (args.has("render")) requireParentFolder(frameName(args.get("render"), first));
    core::Lighting lighting = core::defaultLighting();
    if (args.has("lighting")) {
        const std::string path = args.get("lighting");
        lighting = fromFile(path, [&](const nlohmann::json& j) { return lightingFromJsonFile(j, path); });
    }
    // The views first (a bad file is refused before any frame is read).
    std::vector<int> viewFrames;
    std::vector<core::SolveView> views;
    if (solve) {
        views = readViews(args.get("views"), lighting, &viewFrames);
        for (size_t i = 0; i < views.size(); ++i)
            if (viewFrames[i] < first || viewFrames[i] > last)
                throw InvalidArgument("view '" + views[i].name + "' is on frame " + std::to_string(viewFrames[i]) + ", outside --range");
    }
    core::VolumeLimits limits;
    limits.storage = core::volumeStorageNamed(args.get("storage", "auto"));
    Frames frames = readFrames(args.get("frames"), first, last, fps, solve, limits);
    const core::Volume& firstFrame = frames.volumes.front();
    progressLine(args.has("quiet"), "read " + std::to_string(frames.volumes.size()) + " frames, stored " +
                                        (firstFrame.isSparse() ? "sparse (the first: " + std::to_string(firstFrame.activeVoxels()) + " active voxels)" : "dense"));
    auto device = core::GpuDevice::create();
    if (solve) solveFrames(args, *device, frames, std::move(views), viewFrames, lighting, first, last);
    if (args.has("render")) renderFrames(args, *device, frames.volumes, lighting, first, last);
    return 0;
}

}  // namespace volstyle::cli

// `volstyle solve`: restyle a volume from painted target views (SPEC §4). Reads VIEWS.json
// (cameras, target and weight image paths relative to it, optional lighting), solves, writes the
// VDB, with a progress bar on stderr.

#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/base/errors.h"
#include "core/gpu/gpu_device.h"
#include "core/image/clipped_pixels.h"
#include "core/image/image_io.h"
#include "core/scene/environment_lobes.h"
#include "core/solve/combined_solve.h"
#include "core/solve/light_solver.h"
#include "core/solve/solver.h"
#include "core/volume/vdb_io.h"
#include "protocol/render_json.h"
#include "protocol/solve_json.h"
#include "cli/cli.h"
#include "cli/scene_source.h"

namespace volstyle::cli {
namespace {

namespace fs = std::filesystem;

const CommandSpec kSolve{
    "solve",
    "restyle a volume from painted views",
    "--scene builtin:NAME[:RES]|IN.vdb --views VIEWS.json [options] -o OUT.vdb|LIGHTING.json",
    "Restyles a volume from painted views: finds the emission, albedo or extinction whose\n"
    "single-scattering renders match the targets (bounded least squares, SPEC section 2), reports\n"
    "per view how much of the difference the chosen unknowns cannot reach, and writes the result\n"
    "into the input's grids (docs/FORMATS.md: names, classes and metadata are kept).\n"
    "With --unknowns lights it finds the environment lighting instead (SPEC section 8): the\n"
    "radiances of --lights N lobes, written as a lighting JSON with a lat-long EXR beside it\n"
    "(docs/LIGHTING.md). With lights,emission (or albedo) it alternates between the two and writes\n"
    "OUT.vdb with OUT.lighting.json and OUT.lighting.exr beside it.",
    {
        {"scene", "SRC", "builtin:NAME[:RES] or a .vdb file (required)"},
        {"glass", kGlassValue, kGlassHelp},
        {"views", "VIEWS.json", "{\"views\": [{\"camera\", \"target\": IMAGE, \"weights\"?, \"background\"?: PLATE}], \"lighting\"?} (required)"},
        {"unknowns", "LIST", "emission, albedo, emission,albedo, extinction, lights, or lights with emission and/or albedo; default emission"},
        {"rounds", "N", "lights with emission/albedo: rounds of lights then volume (each --iterations); default 8"},
        {"lights", "N", "lights: the environment's lobes, 1-256 (default: the lighting's environment.lobes, else 16)"},
        {"lobe-domain", "D", "lights: sphere or upper_hemisphere; default sphere (or the lighting's)"},
        {"lights-background", "", "lights: the lobes are the background too, solved with the lighting (background \"lobes\")"},
        {"iterations", "N", "most CGLS iterations; default 30"},
        {"tolerance", "T", "stop when an iteration lowers the objective by less than T, relatively; default 1e-4"},
        {"coarse", "N", "first N iterations on half the unknowns and pixels per axis, as the warm start; default 0"},
        {"visible-change", "V", "stop once two iterations change no constrained pixel by more than V (linear; 0: off); default 0.5/255"},
        {"regularization", "TERMS", "laplacian=W,l2=W,toward_one=W (per unknown: albedo.toward_one=W); default laplacian=0.002"},
        {"basis", "B", "trilinear or box; default trilinear"},
        {"step", "VOXELS", "march step in voxels; default 0.5"},
        {"traversal", "T", "march (equal steps) or exact (voxel cells); default march"},
        {"hull", "H", "extinction (solve only where the medium is) or none; default extinction"},
        {"resolution", "X,Y,Z", "the unknown grid's size; default the volume's"},
        {"medium-radiance", "R,G,B", "L_m, the medium's own radiance: extinction solves need it (try the background's); default none"},
        {"options", "OPTS.json", "solver options as JSON (the API's solve body); flags override it; default none"},
        {"quiet", "", "no progress bar"},
        {"keep-clipped", "", "fit 8/16-bit targets where the picture under the paint was clipped (by default those pixels get weight 0)"},
        {"output", "OUT.vdb", "the result; the folder must exist (required)"},
    },
    "  volstyle solve --scene builtin:cloud:32 --views views.json --unknowns emission,albedo -o out.vdb\n"
    "  volstyle solve --scene builtin:cloud:32 --views views.json --unknowns lights --lights 32 -o sky.json\n"};

}  // namespace

std::vector<core::SolveView> readViews(const std::string& path, core::Lighting& lighting, std::vector<int>* frames, bool clipAware) {
    nlohmann::json j = readJsonFile(path);
    protocol::JsonReader r;
    std::vector<core::SolveView> views;
    const fs::path base = fs::path(path).parent_path();
    if (r.object(j, "", {"views", "lighting"})) {
        if (!j.contains("views") || !j["views"].is_array() || j["views"].empty()) {
            r.fail("/views", "must be a non-empty array of {\"camera\", \"target\", \"weights\"}");
        } else {
            for (size_t i = 0; i < j["views"].size(); ++i) {
                const auto& v = j["views"][i];
                const std::string p = "/views/" + std::to_string(i);
                const bool known = frames ? r.object(v, p, {"name", "camera", "target", "weights", "background", "frame"})
                                          : r.object(v, p, {"name", "camera", "target", "weights", "background"});
                if (!known) continue;
                if (frames) {
                    const auto frame = v.contains("frame") ? r.integer(v["frame"], p + "/frame") : std::nullopt;
                    if (!v.contains("frame")) r.fail(p + "/frame", "each view of an animation names its frame");
                    frames->push_back(frame.value_or(0));
                }
                core::SolveView view;
                view.name = v.contains("name") ? r.string(v["name"], p + "/name").value_or("") : "v" + std::to_string(i + 1);
                if (!v.contains("camera") || !v.contains("target")) {
                    r.fail(p, "needs \"camera\" and \"target\"");
                    continue;
                }
                try {
                    view.camera = protocol::cameraFromJson(v["camera"], p + "/camera");
                } catch (const protocol::ValidationError& e) {
                    for (const auto& d : e.details()) r.fail(d.path, d.message);
                }
                auto target = r.string(v["target"], p + "/target");
                auto weights = v.contains("weights") ? r.string(v["weights"], p + "/weights") : std::nullopt;
                auto plate = v.contains("background") ? r.string(v["background"], p + "/background") : std::nullopt;
                if (!r.ok()) continue;
                const core::LoadedImage loaded = core::loadImage((base / *target).string());
                view.target = core::pictureOf(loaded);  // a render EXR: its picture
                // Painted over an 8/16-bit picture: where it was clipped, the paint says nothing.
                if (loaded.wasSrgb && clipAware) view.clippedPixels = core::ignoreClippedPixels(view.target);
                if (weights) view.weights = core::loadImage((base / *weights).string()).image;
                if (plate) view.background = std::make_shared<const core::Image>(core::loadImage((base / *plate).string()).image);
                views.push_back(std::move(view));
            }
        }
        if (j.contains("lighting")) {
            try {
                lighting = lightingFromJsonFile(j["lighting"], path, "/lighting");
            } catch (const protocol::ValidationError& e) {
                for (const auto& d : e.details()) r.fail(d.path, d.message);
            }
        }
    }
    try {
        r.throwIfErrors();
    } catch (const protocol::ValidationError& e) {
        throw InvalidArgument("'" + path + "': " + e.what());
    }
    return views;
}

namespace {

/// One line, redrawn in place on a terminal, appended otherwise (logs).
class ProgressBar {
public:
    ProgressBar(int total, bool quiet) : m_total(total), m_quiet(quiet), m_isTty(isatty(fileno(stderr))) {}
    void update(const core::SolveProgress& p) {
        if (m_quiet || p.phase != core::SolvePhase::Iterating) return;  // the bar counts iterations
        const int width = 24, filled = std::min(width, width * p.iteration / std::max(1, m_total));
        double rms = 0;
        for (double x : p.rmsPerView) rms += x / double(p.rmsPerView.size());
        std::fprintf(stderr, "%s[%s%s] %3d/%d  objective %.4g  RMS %.4g  %.1f s", m_isTty ? "\r" : "",
                     std::string(size_t(filled), '#').c_str(), std::string(size_t(width - filled), '.').c_str(),
                     p.iteration, m_total, p.objective, rms, p.elapsedMs / 1000);
        std::fputs(m_isTty ? "" : "\n", stderr);
        std::fflush(stderr);
    }
    void finish() {
        if (!m_quiet && m_isTty) std::fputs("\n", stderr);
    }

private:
    int m_total;
    bool m_quiet, m_isTty;
};

/// `--regularization laplacian=0.002,albedo.toward_one=0.01`: "unknown.term" sets one unknown's
/// weight, starting from the shared ones.
void applyRegularizationFlag(const std::string& value, core::SolveOptions& opt) {
    for (const auto& kv : split(value, ',')) {
        auto eq = kv.find('=');
        if (eq == std::string::npos) throw InvalidArgument("--regularization takes name=value pairs, got '" + kv + "'");
        std::string name = kv.substr(0, eq);
        const double weight = numbers("regularization", kv.substr(eq + 1), 1)[0];
        core::Regularization* reg = &opt.regularization;
        if (auto dot = name.find('.'); dot != std::string::npos) {
            const std::string unknown = name.substr(0, dot);
            auto& slot = unknown == "emission" ? opt.emissionRegularization : opt.albedoRegularization;
            if (unknown != "emission" && unknown != "albedo")
                throw InvalidArgument("--regularization: '" + unknown + "' is not emission or albedo");
            if (!slot) slot = opt.regularization;
            reg = &*slot;
            name = name.substr(dot + 1);
        }
        if (name == "laplacian") reg->laplacian = weight;
        else if (name == "l2") reg->l2 = weight;
        else if (name == "toward_one") reg->towardOne = weight;
        else throw InvalidArgument("--regularization: unknown term '" + name + "'; terms: laplacian, l2, toward_one (optionally emission. or albedo.)");
    }
}

/// One of `choices` for `--flag`, or InvalidArgument listing them.
std::string choice(const Arguments& args, const std::string& flag, const std::vector<std::string>& choices) {
    const std::string v = args.get(flag);
    for (const auto& c : choices)
        if (v == c) return v;
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : " or ") + c;
    throw InvalidArgument("--" + flag + " must be " + list);
}

/// Options: defaults, then OPTS.json, then flags; validated.
core::SolveOptions solveOptions(const Arguments& args, const core::Lighting& lighting) {
    core::SolveOptions opt;
    if (args.has("options"))
        opt = fromFile(args.get("options"), [&](const nlohmann::json& j) { return protocol::solveOptionsFromJson(j, "", opt); });
    std::vector<std::string> volumeUnknowns;
    if (args.has("unknowns"))
        for (const auto& u : split(args.get("unknowns"), ','))
            if (u != "lights") volumeUnknowns.push_back(u);
    if (!volumeUnknowns.empty()) {
        auto u = protocol::parseUnknowns(volumeUnknowns);
        if (!u) throw InvalidArgument("--unknowns must be emission, albedo, emission,albedo, extinction or lights");
        opt.unknown = *u;
    }
    if (args.has("iterations")) opt.maxIterations = int(args.number("iterations", opt.maxIterations));
    if (args.has("tolerance")) opt.tolerance = args.number("tolerance", opt.tolerance);
    if (args.has("coarse")) opt.coarseIterations = int(args.number("coarse", opt.coarseIterations));
    if (args.has("visible-change")) opt.visibleChange = args.number("visible-change", opt.visibleChange);
    if (args.has("step")) opt.stepVoxels = args.number("step", opt.stepVoxels);
    if (args.has("basis")) opt.basis = choice(args, "basis", {"trilinear", "box"}) == "box" ? core::BasisType::Box : core::BasisType::Trilinear;
    if (args.has("traversal")) opt.exactTraversal = choice(args, "traversal", {"march", "exact"}) == "exact";
    if (args.has("hull")) opt.useHull = choice(args, "hull", {"extinction", "none"}) == "extinction";
    if (args.has("regularization")) applyRegularizationFlag(args.get("regularization"), opt);
    if (args.has("resolution")) {
        auto r = numbers("resolution", args.get("resolution"), 3);
        opt.resolution = Int3{int(r[0]), int(r[1]), int(r[2])};
    }
    if (args.has("medium-radiance")) {
        auto m = numbers("medium-radiance", args.get("medium-radiance"), 3);
        opt.mediumRadiance = Vec3d(m[0], m[1], m[2]);
    }
    if (opt.unknown == core::Unknown::Extinction && !opt.mediumRadiance) {
        const Vec3d b = lighting.background.color;  // a good start: where the medium is opaque it hides the background
        throw InvalidArgument(fmt::format("an extinction solve needs --medium-radiance R,G,B, the radiance the medium shows "
                                          "where it is opaque (TVCG Sec. 4.2.4); e.g. the background's: --medium-radiance {:g},{:g},{:g}",
                                          b.x, b.y, b.z));
    }
    opt.validate();
    return opt;
}

double meanOf(const std::vector<double>& v) {
    double sum = 0;
    for (double x : v) sum += x / double(v.size());
    return sum;
}

/// Writes the lighting (with the solved lobes) as JSON at `json` and its lobes as a lat-long EXR
/// of the same name beside it; returns the EXR's path.
std::string writeLighting(const core::Lighting& lighting, const std::string& json) {
    {
        std::ofstream out(json);
        out << protocol::toText(protocol::lightingToJson(lighting), 2) << "\n";
        if (!out.flush()) throw InvalidArgument("cannot write '" + json + "'");
    }
    const std::string exr = fs::path(json).replace_extension(".exr").string();
    core::saveImage(exr, core::lobesToLatLong(lighting.environment.basis(), core::lobeRadiance(lighting.environment), 512, 256));
    return exr;
}

/// `--unknowns lights` (alone, or with emission and/or albedo): the environment lobes' radiances
/// (LightSolver), or both blocks in turn (solveLightsAndVolume). Lights alone write the lighting
/// JSON at `output` with a lat-long EXR beside it; with the volume, `output` is the VDB and the
/// lighting goes to OUT.lighting.json / .exr.
int runLightSolve(const Arguments& args, core::Lighting lighting, std::vector<core::SolveView> views,
                  const core::SolveOptions& opt, const std::string& output, bool withVolume) {
    core::SolveOptions::Lights lightOptions = opt.lights;  // OPTS.json's "lights", then the flags
    if (args.has("lights-background")) lightOptions.background = true;
    if (args.has("lights")) {
        const double n = args.number("lights", 16);
        if (!(n >= core::kMinLobes && n <= core::kMaxLobes && n == std::floor(n)))
            throw InvalidArgument("--lights must be a whole number in [1, 256], got '" + args.get("lights") + "'");
        lightOptions.lobes = int(n);
    }
    if (args.has("lobe-domain"))
        lightOptions.domain = choice(args, "lobe-domain", {"sphere", "upper_hemisphere"}) == "sphere" ? core::LobeDomain::Sphere
                                                                                                      : core::LobeDomain::UpperHemisphere;
    lighting = core::lightingForLightSolve(lighting, lightOptions);
    core::EnvironmentLight& env = lighting.environment;

    core::Volume volume = loadScene(args.get("scene"));
    applyGlassOption(args, volume);
    auto device = core::GpuDevice::create();
    if (withVolume) {
        const int rounds = int(args.number("rounds", 8));
        if (rounds < 1 || rounds > 100) throw InvalidArgument("--rounds must be in [1, 100]");
        ProgressBar bar(opt.maxIterations, args.has("quiet"));
        const core::CombinedSolveResult result = core::solveLightsAndVolume(
            *device, volume, lighting, views, opt, rounds, [&](const core::CombinedProgress& p) { bar.update(p.inner); });
        bar.finish();
        core::saveVdb(output, result.volume);
        env.setRadiance(result.radiance);
        const std::string json = fs::path(output).replace_extension(".lighting.json").string();
        const std::string exr = writeLighting(lighting, json);
        std::fprintf(stderr, "lights and %s: %d rounds, RMS %.4g -> %.4g, %.2f s; wrote %s, %s and %s\n", core::unknownName(opt.unknown),
                     result.rounds, result.rmsHistory.front(), result.rmsHistory.back(), result.totalMs / 1000, output.c_str(),
                     json.c_str(), exr.c_str());
        return 0;
    }
    core::LightSolver solver(*device, volume, lighting, std::move(views), opt);
    ProgressBar bar(opt.maxIterations, args.has("quiet"));
    const core::LightSolveResult result = solver.run([&](const core::SolveProgress& p) { bar.update(p); });
    bar.finish();

    env.setRadiance(result.radiance);
    const std::string exr = writeLighting(lighting, output);
    const auto& rep = result.report;
    std::fprintf(stderr, "lights: %d lobes, %d iterations (%s), RMS %.4g -> %.4g, %.2f s (forward %.2f, back-projection %.2f; "
                         "light volumes %.2f s, %.1f MiB); wrote %s and %s\n",
                 env.lobes, rep.iterations, core::stopReasonName(rep.stopReason), meanOf(rep.initialRms), meanOf(rep.finalRms),
                 rep.totalMs / 1000, rep.forwardMs / 1000, rep.adjointMs / 1000, result.lightVolumeMs / 1000,
                 double(result.lightVolumeBytes) / (1 << 20), output.c_str(), exr.c_str());
    return 0;
}

}  // namespace

const CommandSpec& solveCommand() { return kSolve; }

int runSolve(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, kSolve);
    if (printHelpIfAsked(args, kSolve)) return 0;
    for (const char* required : {"scene", "views", "output"})
        if (!args.has(required))
            throw InvalidArgument(std::string(std::string(required) == "output" ? "-o OUT.vdb" : "--" + std::string(required)) +
                                  " is required (volstyle solve --help)");
    const std::string output = args.get("output");
    std::vector<std::string> unknowns = args.has("unknowns") ? split(args.get("unknowns"), ',') : std::vector<std::string>{};
    const bool lights = std::find(unknowns.begin(), unknowns.end(), "lights") != unknowns.end();
    const bool withVolume = lights && unknowns.size() > 1;
    if (lights && !withVolume && fs::path(output).extension() != ".json")
        throw InvalidArgument("--unknowns lights writes a lighting: -o must end in .json, got '" + output + "'");
    if ((!lights || withVolume) && fs::path(output).extension() != ".vdb") throw InvalidArgument("-o must end in .vdb, got '" + output + "'");
    if (!lights && (args.has("lights") || args.has("lobe-domain") || args.has("rounds") || args.has("lights-background")))
        throw InvalidArgument("--lights, --lobe-domain, --rounds and --lights-background need --unknowns lights");
    requireParentFolder(output);  // before the work, not after it
    core::Lighting lighting = core::defaultLighting();
    std::vector<core::SolveView> views = readViews(args.get("views"), lighting, nullptr, !args.has("keep-clipped"));
    const core::SolveOptions opt = solveOptions(args, lighting);
    if (lights) return runLightSolve(args, lighting, std::move(views), opt, output, withVolume);

    core::Volume volume = loadScene(args.get("scene"));
    applyGlassOption(args, volume);

    auto device = core::GpuDevice::create();
    core::Solver solver(*device, volume, lighting, std::move(views), opt);
    ProgressBar bar(opt.maxIterations, args.has("quiet"));
    core::SolveResult result = solver.run([&](const core::SolveProgress& p) { bar.update(p); });
    bar.finish();

    core::saveVdb(output, result.volume);
    const auto& rep = result.report;
    std::fprintf(stderr, "%s: %d iterations (%s), RMS %.4g -> %.4g, %.2f s (forward %.2f, back-projection %.2f, vectors %.2f); wrote %s\n",
                 core::unknownName(opt.unknown), rep.iterations, core::stopReasonName(rep.stopReason), meanOf(rep.initialRms),
                 meanOf(rep.finalRms), rep.totalMs / 1000, rep.forwardMs / 1000, rep.adjointMs / 1000, rep.vectorMs / 1000,
                 output.c_str());
    // What the wait was made of (issue #40): the set-up phase by phase, then one iteration.
    std::string phases;
    for (const auto& [name, ms] : rep.setupPhases) phases += fmt::format("{}{} {:.0f}", phases.empty() ? "" : ", ", name, ms);
    const int n = std::max(rep.iterations, 1);
    std::fprintf(stderr, "  set-up %.2f s (%s ms); per iteration %.1f ms: forward %.1f, back-projection %.1f, vectors %.1f; "
                 "%zu unknowns, %zu in the hull, %zu constrained pixels, %zu of %zu views from cached rows\n",
                 rep.setupMs() / 1000, phases.c_str(), (rep.forwardMs + rep.adjointMs + rep.vectorMs) / n, rep.forwardMs / n,
                 rep.adjointMs / n, rep.vectorMs / n, rep.unknownCount, rep.hullCount, rep.constraintPixels, rep.cachedViews,
                 rep.initialRms.size());
    for (size_t v = 0; v < rep.reach.unreachableRms.size() && v < rep.finalRms.size(); ++v)
        std::fprintf(stderr, "  view %zu: RMS %.4g, of which %.4g is out of reach of %s\n", v + 1, rep.finalRms[v],
                     rep.reach.unreachableRms[v], core::unknownName(opt.unknown));
    if (!rep.reach.advice.empty()) std::fprintf(stderr, "note: %s\n", rep.reach.advice.c_str());
    spdlog::info("reach analysis: {:.0f} ms", rep.reach.ms);
    return 0;
}

}  // namespace volstyle::cli

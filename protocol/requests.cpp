#include "protocol/requests.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <sstream>

#include "protocol/render_json.h"
#include "protocol/solve_json.h"

namespace volstyle::protocol {

std::string exposureProblem(double stops) {
    if (stops >= -kMaxExposureStops && stops <= kMaxExposureStops) return "";
    return "must be in [-" + std::to_string(int(kMaxExposureStops)) + ", " + std::to_string(int(kMaxExposureStops)) + "] stops";
}

const char* imageFormatName(ImageFormat f) { return f == ImageFormat::Png ? "png" : f == ImageFormat::Jpeg ? "jpeg" : "exr"; }
const char* imageMimeType(ImageFormat f) {
    return f == ImageFormat::Png ? "image/png" : f == ImageFormat::Jpeg ? "image/jpeg" : "image/x-exr";
}

core::Camera readCamera(JsonReader& r, const nlohmann::json& body, const std::string& path, const RequestLimits& limits) {
    const std::string key = path.substr(path.rfind('/') + 1);
    core::Camera camera;
    if (!body.contains(key)) {
        r.fail(path, "is required");
        return camera;
    }
    try {
        camera = cameraFromJson(body[key], path);
    } catch (const ValidationError& e) {
        for (const auto& d : e.details()) r.fail(d.path, d.message);
        return camera;
    }
    for (auto [side, name] : {std::pair{camera.width, "width"}, std::pair{camera.height, "height"}})
        if (side > limits.maxImageSide) {
            const std::string message = "images are limited to " + std::to_string(limits.maxImageSide) + " pixels a side";
            throw ApiError(ErrorCode::TooLarge, message, {{path + "/" + name, message}});
        }
    return camera;
}

CreateSessionRequest CreateSessionRequest::fromJson(const nlohmann::json& j, const RequestLimits& limits) {
    JsonReader r;
    CreateSessionRequest q;
    if (r.object(j, "", {"scene", "resolution"})) {
        if (j.contains("scene")) q.scene = r.string(j["scene"], "/scene").value_or(q.scene);
        if (j.contains("resolution")) q.resolution = r.integer(j["resolution"], "/resolution").value_or(q.resolution);
        if (q.scene.rfind("builtin:", 0) != 0) r.fail("/scene", "must be builtin:NAME (upload a VDB with PUT …/volume instead)");
        if (q.resolution < limits.minSceneResolution || q.resolution > limits.maxSceneResolution)
            r.fail("/resolution", "must be in [" + std::to_string(limits.minSceneResolution) + ", " +
                                      std::to_string(limits.maxSceneResolution) + "]");
    }
    r.throwIfErrors();
    return q;
}

RenderRequest RenderRequest::fromJson(const nlohmann::json& j, const RequestLimits& limits) {
    JsonReader r;
    RenderRequest q;
    if (r.object(j, "", {"camera", "format", "exposure", "mode", "translucent", "exr_type"})) {
        q.camera = readCamera(r, j, "/camera", limits);
        if (j.contains("format")) {
            auto f = r.string(j["format"], "/format");
            if (f == "png") q.format = ImageFormat::Png;
            else if (f == "jpeg" || f == "jpg") q.format = ImageFormat::Jpeg;  // previews: a few ms to encode, a fifth of the bytes
            else if (f == "exr") q.format = ImageFormat::Exr;
            else if (f) r.fail("/format", "must be 'png', 'jpeg' or 'exr', got '" + *f + "'");
        }
        if (j.contains("exposure")) q.exposure = r.number(j["exposure"], "/exposure").value_or(0);
        if (auto why = exposureProblem(q.exposure); !why.empty()) r.fail("/exposure", why);
        if (j.contains("exr_type")) {
            const auto t = r.string(j["exr_type"], "/exr_type");
            if (t == "float") q.exrHalf = false;
            else if (t && *t != "half") r.fail("/exr_type", "must be 'half' or 'float'");
        }
        if (j.contains("mode")) {
            const auto m = r.string(j["mode"], "/mode");
            if (m == "translucent") q.mode = RenderMode::Translucent;
            else if (m && *m != "single_scattering") r.fail("/mode", "must be 'single_scattering' or 'translucent'");
        }
        if (j.contains("translucent")) {
            if (q.mode != RenderMode::Translucent) r.fail("/translucent", "needs \"mode\": \"translucent\"");
            try {
                q.translucent = translucentFromJson(j["translucent"], "/translucent");
            } catch (const ValidationError& e) {
                for (const auto& d : e.details()) r.fail(d.path, d.message);
            }
        }
    }
    r.throwIfErrors();
    return q;
}

AddViewRequest AddViewRequest::fromJson(const nlohmann::json& j, const RequestLimits& limits) {
    JsonReader r;
    AddViewRequest q;
    if (r.object(j, "", {"camera", "frame"})) {
        q.camera = readCamera(r, j, "/camera", limits);
        if (j.contains("frame")) {
            q.frame = r.integer(j["frame"], "/frame");
            if (q.frame && (*q.frame < 0 || *q.frame > kMaxFrameNumber)) r.fail("/frame", "must be in [0, " + std::to_string(kMaxFrameNumber) + "]");
        }
    }
    r.throwIfErrors();
    return q;
}

AnimateRequest AnimateRequest::fromJson(const nlohmann::json& j) {
    JsonReader r;
    AnimateRequest q;
    if (r.object(j, "", {"unknowns", "temporal", "sweeps", "max_iterations", "follow_flow", "fps"})) {
        if (j.contains("unknowns")) {
            const auto& u = j["unknowns"];
            if (u == nlohmann::json::array({"emission"})) q.albedo = false;
            else if (u == nlohmann::json::array({"albedo"})) q.albedo = true;
            else r.fail("/unknowns", "must be [\"emission\"] or [\"albedo\"]");
        }
        if (j.contains("temporal")) q.temporal = r.number(j["temporal"], "/temporal").value_or(q.temporal);
        if (j.contains("sweeps")) q.sweeps = r.integer(j["sweeps"], "/sweeps").value_or(q.sweeps);
        if (j.contains("max_iterations")) q.maxIterations = r.integer(j["max_iterations"], "/max_iterations").value_or(q.maxIterations);
        if (j.contains("follow_flow")) q.followFlow = r.boolean(j["follow_flow"], "/follow_flow").value_or(q.followFlow);
        if (j.contains("fps")) q.fps = r.number(j["fps"], "/fps").value_or(q.fps);
        if (!(q.temporal >= 0 && q.temporal <= 1e9)) r.fail("/temporal", "must be in [0, 1e9]");
        if (q.sweeps < 1 || q.sweeps > 100) r.fail("/sweeps", "must be in [1, 100]");
        if (q.maxIterations < 1 || q.maxIterations > 10000) r.fail("/max_iterations", "must be in [1, 10000]");
        if (!(q.fps > 0 && q.fps <= 1000)) r.fail("/fps", "must be in (0, 1000]");
    }
    r.throwIfErrors();
    return q;
}

FramesRenderRequest FramesRenderRequest::fromJson(const nlohmann::json& j, const RequestLimits& limits) {
    JsonReader r;
    FramesRenderRequest q;
    if (r.object(j, "", {"camera", "exposure"})) {
        if (!j.contains("camera")) r.fail("/camera", "is required");
        else q.camera = readCamera(r, j, "/camera", limits);
        if (j.contains("exposure")) q.exposure = r.number(j["exposure"], "/exposure").value_or(0);
        if (auto why = exposureProblem(q.exposure); !why.empty()) r.fail("/exposure", why);
    }
    r.throwIfErrors();
    return q;
}

RevertRequest RevertRequest::fromJson(const nlohmann::json& j) {
    JsonReader r;
    RevertRequest q;
    if (r.object(j, "", {"version"})) {
        if (!j.contains("version")) r.fail("/version", "is required");
        else q.version = r.integer(j["version"], "/version").value_or(0);
    }
    r.throwIfErrors();
    return q;
}

SetLightingRequest SetLightingRequest::fromJson(const nlohmann::json& j) { return {lightingFromJson(j)}; }

SolveRequest SolveRequest::fromJson(const nlohmann::json& j, const RequestLimits& limits, const Vec3d* background) {
    SolveRequest q;
    try {
        q.options = solveOptionsFromJson(j);
    } catch (const ValidationError& e) {
        // An extinction solve without L_m: the session's background is a good start. Decided by the
        // field's absence, not by the wording of the problem.
        if (!background || !j.is_object() || j.contains("medium_radiance")) throw;
        std::ostringstream hint;  // %g-like: six significant digits
        hint << "; e.g. the background's, \"medium_radiance\": [" << background->x << ", " << background->y << ", " << background->z << "]";
        auto details = e.details();
        for (auto& d : details)
            if (d.path == "/medium_radiance") d.message += hint.str();
        throw ValidationError(details);
    }
    if (q.options.resolution && q.options.resolution->volume() > limits.maxSolveVoxels) {
        const Int3 r = *q.options.resolution;
        const std::string message = std::to_string(r.x) + "x" + std::to_string(r.y) + "x" + std::to_string(r.z) +
                                    " unknowns per grid is over the limit of " + std::to_string(limits.maxSolveVoxels) + " voxels";
        throw ApiError(ErrorCode::TooLarge, message, {{"/resolution", message}});
    }
    return q;
}

namespace {

/// The last value of `name`, if given.
std::optional<std::string> lastValue(const QueryParams& params, const std::string& name) {
    auto [lo, hi] = params.equal_range(name);
    if (lo == hi) return std::nullopt;
    return std::prev(hi)->second;
}

/// The whole text as a number of type T, or nothing (no trailing characters, no NaN or ±inf).
template <typename T>
std::optional<T> parseWhole(const std::string& text) {
    T value{};
    const char* end = text.data() + text.size();
    auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (ec != std::errc() || ptr != end || text.empty()) return std::nullopt;
    if constexpr (std::is_floating_point_v<T>)
        if (!std::isfinite(value)) return std::nullopt;
    return value;
}

}  // namespace

ViewRenderQuery ViewRenderQuery::fromQuery(const QueryParams& params) {
    JsonReader r;
    ViewRenderQuery q;
    if (auto text = lastValue(params, "exposure")) {
        auto v = parseWhole<double>(*text);
        if (!v) r.fail("?exposure", "must be a finite number of stops, got '" + *text + "'");
        else if (auto why = exposureProblem(*v); !why.empty()) r.fail("?exposure", why + ", got '" + *text + "'");
        else q.exposure = *v;
    }
    if (auto text = lastValue(params, "exr_type")) {
        if (*text == "float") q.exrHalf = false;
        else if (*text != "half") r.fail("?exr_type", "must be 'half' or 'float', got '" + *text + "'");
    }
    r.throwIfErrors();
    return q;
}

ListQuery ListQuery::fromQuery(const QueryParams& params, bool bySession) {
    JsonReader r;
    ListQuery q;
    if (auto text = lastValue(params, "limit")) {
        auto v = parseWhole<int>(*text);
        if (!v || *v < 1 || *v > kMaxLimit) r.fail("?limit", "must be an integer in [1, " + std::to_string(kMaxLimit) + "], got '" + *text + "'");
        else q.limit = *v;
    }
    if (auto text = lastValue(params, "cursor")) {
        const bool hex = text->size() <= 256 && std::all_of(text->begin(), text->end(), [](char c) { return std::isxdigit((unsigned char)c); });
        if (text->empty() || !hex) r.fail("?cursor", "must be the cursor a page's Link header names");
        else q.cursor = *text;
    }
    if (auto text = lastValue(params, "session")) {
        if (!bySession) r.fail("?session", "this list has no session filter");
        else q.session = *text;
    }
    r.throwIfErrors();
    return q;
}

VolumeQuery VolumeQuery::fromQuery(const QueryParams& params) {
    JsonReader r;
    VolumeQuery q;
    if (auto text = lastValue(params, "version")) {
        auto v = parseWhole<int>(*text);
        if (!v || *v < 1) r.fail("?version", "must be a version number (an integer >= 1), got '" + *text + "'");
        else q.version = *v;
    }
    r.throwIfErrors();
    return q;
}

}  // namespace volstyle::protocol

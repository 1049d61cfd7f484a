#pragma once
/// \file requests.h
/// Every request body and query string of the API as a typed value, parsed once at the door:
/// `fromJson(json, limits)` / `fromQuery(params)` list every invalid field with its JSON Pointer
/// (query parameters as `?name`) and throw ValidationError, so handlers only ever see valid input.
/// Unknown body fields are rejected; unknown query parameters are ignored (pages add cache
/// busters such as `?t=…`).

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_options.h"
#include "protocol/render_json.h"
#include "protocol/validation.h"

namespace volstyle::protocol {

/// The server's limits that decide what a request may ask for (SPEC §3 Limits).
struct RequestLimits {
    int maxImageSide = 4096;        ///< camera width and height, in pixels
    int minSceneResolution = 8;     ///< built-in scenes' voxels a side
    int maxSceneResolution = 256;
    int64_t maxSolveVoxels = int64_t(256) * 256 * 256;  ///< a solve's unknown grid (its "resolution")
};

/// Query parameters as the HTTP layer hands them over (name → value, repeats allowed).
using QueryParams = std::multimap<std::string, std::string>;

enum class ImageFormat { Png, Exr, Jpeg };  ///< JPEG: 8-bit sRGB like PNG, for live frames
const char* imageFormatName(ImageFormat f);
const char* imageMimeType(ImageFormat f);

/// The camera block of a request at `path` (required): its problems are recorded into `r` like
/// any other field's; over the image-side limit it throws ApiError too_large (413) naming the
/// limit. The one place cameras in requests are read.
core::Camera readCamera(JsonReader& r, const nlohmann::json& body, const std::string& path, const RequestLimits& limits);

/// POST /sessions: {"scene": "builtin:NAME", "resolution": N}, both optional.
struct CreateSessionRequest {
    std::string scene = "builtin:cloud";
    int resolution = 128;
    std::string builtinName() const { return scene.substr(8); }  ///< NAME of builtin:NAME
    static CreateSessionRequest fromJson(const nlohmann::json& j, const RequestLimits& limits);
};

/// POST /sessions/{sid}/render: {"camera": {…}, "format": "png"|"exr", "exposure": 0, "mode": "single_scattering"}.
enum class RenderMode { SingleScattering, Translucent };

struct RenderRequest {
    core::Camera camera;
    ImageFormat format = ImageFormat::Png;
    double exposure = 0;  ///< stops, PNG only
    bool exrHalf = true;  ///< "exr_type": "half" (default, pictures) or "float" (data: targets, CT)
    RenderMode mode = RenderMode::SingleScattering;
    core::TranslucentSettings translucent;  ///< "translucent": {…} (mode "translucent" only)
    static RenderRequest fromJson(const nlohmann::json& j, const RequestLimits& limits);
};

/// Exposure in stops, either way: 2^±30 covers any picture; beyond it every pixel is black or
/// white (and 2^1e308 is infinite).
constexpr double kMaxExposureStops = 30;
/// The one check of an exposure (every request that takes one; the schema says the same):
/// "must be in [-30, 30] stops", or empty.
std::string exposureProblem(double stops);

/// The largest frame number of an animation (10 minutes at 60 fps and then some).
constexpr int kMaxFrameNumber = 99999;

/// POST /sessions/{sid}/views: {"camera": {…}, "frame"?: N} (a frame of the animation).
struct AddViewRequest {
    core::Camera camera;
    std::optional<int> frame;
    static AddViewRequest fromJson(const nlohmann::json& j, const RequestLimits& limits);
};

/// POST /sessions/{sid}/animate (docs/ANIMATION.md): the key-frame solve's options.
struct AnimateRequest {
    bool albedo = false;        ///< "unknowns": ["emission"] (default) or ["albedo"]
    double temporal = 0.05;
    int sweeps = 3;
    int maxIterations = 30;
    bool followFlow = true;     ///< "follow_flow"
    double fps = 24;            ///< turns the frames' `vel` grids (units per second) into units per frame
    static AnimateRequest fromJson(const nlohmann::json& j);
};

/// POST /sessions/{sid}/frames/render: {"camera": {…}, "exposure"?: stops}.
struct FramesRenderRequest {
    core::Camera camera;
    double exposure = 0;
    static FramesRenderRequest fromJson(const nlohmann::json& j, const RequestLimits& limits);
};

/// POST /sessions/{sid}/revert: {"version": N}.
struct RevertRequest {
    int version = 0;
    static RevertRequest fromJson(const nlohmann::json& j);
};

/// PUT /sessions/{sid}/lighting: the lighting object (render_json.h); no server-side paths.
/// PUT /sessions/{sid}/lighting: "session" in it names the session's map (resolved by the service).
struct SetLightingRequest {
    LightingRequest lighting;
    static SetLightingRequest fromJson(const nlohmann::json& j);
};

/// POST /sessions/{sid}/solve: the solver options (solve_json.h); a `resolution` over
/// maxSolveVoxels is too_large (413).
struct SolveRequest {
    core::SolveOptions options;
    /// `background`, if given (the session's background colour), is offered as a starting value
    /// when an extinction solve leaves out "medium_radiance".
    static SolveRequest fromJson(const nlohmann::json& j, const RequestLimits& limits, const Vec3d* background = nullptr);
};

/// GET …/views/{vid}/render.{png,exr}?exposure=STOPS.
struct ViewRenderQuery {
    double exposure = 0;
    bool exrHalf = true;  ///< ?exr_type=half (default) or float
    static ViewRenderQuery fromQuery(const QueryParams& params);
};

/// GET /sessions and GET /jobs: ?limit=N (1–1000, default 100) items after ?cursor=C (the
/// `Link: <…>; rel="next"` of the page before names it); GET /jobs also ?session=SID.
struct ListQuery {
    static constexpr int kDefaultLimit = 100, kMaxLimit = 1000;
    int limit = kDefaultLimit;
    std::string cursor;   ///< empty: from the first
    std::string session;  ///< GET /jobs: only this session's; empty: all
    static ListQuery fromQuery(const QueryParams& params, bool bySession);
};

/// GET /sessions/{sid}/volume.vdb?version=N (default: the newest).
struct VolumeQuery {
    std::optional<int> version;
    static VolumeQuery fromQuery(const QueryParams& params);
};

}  // namespace volstyle::protocol

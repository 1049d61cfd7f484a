#pragma once
/// \file stylize_json.h
/// The light-shaft stylizer's scene as JSON (SPEC §7), shared by the CLI's SCENE.json and (next)
/// the API's stylizer resource:
///   {"occluders": [{"name": "tree", "mesh": "tree.obj", "transform": [16 numbers, column-major],
///                   "colour": [0.4, 0.35, 0.3],
///                   "manipulation": {"closing": {"radius_px": 4, "shape": "disc"}}}],
///    "light": {"type": "directional", "direction": [x,y,z], "irradiance": [r,g,b],
///              "shadow_map_size": 2048},
///    "medium": {"extinction": 0.05, "albedo": 0.9, "phase": {"type": "henyey_greenstein", "g": 0.4}},
///    "transfer_function": {"image": "tf.png", "mode": "multiply"|"replace", "depth_range": [0, 50]},
///    "camera": {…SPEC §1…}, "background": [r,g,b], "time": 0,
///    "keyframes": [{"time": 0, "camera": {…}, "transfer_function": {…}}, …]}  (issue #15: a camera path)
/// Meshes are references the caller resolves (the CLI: paths relative to the file; the API: the
/// names of uploaded occluder meshes or builtin:forest/NAME). `volume` is a heterogeneous medium
/// (issue #15): {"source": "session" | "cloud.vdb" | "builtin:NAME", "box": [[x0,y0,z0],[x1,y1,z1]]
/// (default: the volume's bounds), "extinction_scale": 1, "light_transmittance": true, "steps": 128}.

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "core/stylize/scene.h"
#include "protocol/requests.h"
#include "protocol/tf_json.h"
#include "protocol/validation.h"

namespace volstyle::protocol {

/// Where a mesh reference points: the built-in meshes are builtin:forest/ground and
/// builtin:forest/trees; any other reference names an uploaded mesh.
inline const std::string kBuiltinMeshPrefix = "builtin:forest/";

/// The built-in mesh `ref` names (builtin:forest/ground, builtin:forest/trees, built once and
/// shared); null for any other.
std::shared_ptr<const core::Mesh> builtinMesh(const std::string& ref);

struct StylizerSceneRequest {
    core::StylizerScene scene;          ///< occluders with empty meshes, in file order
    std::vector<std::string> meshRefs;  ///< each occluder's `mesh`
    /// The images the transfer function needs (its own, or its image layers'), left for the caller
    /// to load and attach (attachTfImage).
    std::vector<TfImageRef> tfImages;
    /// `volume.source`: "session" (the API's only one), a VDB path or builtin:NAME (files); the
    /// grid is the caller's to attach. `volumeBoxGiven`: false when the box is left to the
    /// volume's own bounds.
    std::string volumeSource;
    bool volumeBoxGiven = false;
};

/// Throws ValidationError listing every invalid field (paths below `path`).
StylizerSceneRequest stylizerSceneFromJson(const nlohmann::json& j, const std::string& path = "",
                                           SceneSource source = SceneSource::File);

/// The outputs' names (SPEC §7): "frame", "average_visibility", "linear_depth", "shadow_map",
/// "modified_shadow_map", "scattering"; nullopt for any other.
/// Gives the TF `ref` names (the scene's or key ref.key's) the image `image`: the TF's own
/// (ref.layer −1) or its image layer's.
void attachTfImage(core::StylizerScene& scene, const TfImageRef& ref, std::shared_ptr<const core::Image> image);

std::optional<core::StylizerOutput> stylizerOutputFromName(const std::string& name);
/// The AOVs' names, for messages: "average_visibility, linear_depth, …".
extern const char* const kStylizerAovNames;

/// POST /sessions/{sid}/stylizer/frame: {"camera": {…} (default: the scene's), "format":
/// "png"|"jpeg"|"exr", "aov": NAME, "time": T (default: the scene's), "method":
/// "accelerated"|"naive", "steps": N, "exposure": STOPS}, all optional.
struct StylizerFrameRequest {
    std::optional<core::Camera> camera;
    ImageFormat format = ImageFormat::Png;
    core::StylizerOutput output = core::StylizerOutput::Frame;
    std::optional<double> time;
    core::StylizeSettings settings;
    double exposure = 0;  ///< stops, PNG and JPEG
    static StylizerFrameRequest fromJson(const nlohmann::json& j, const RequestLimits& limits);
};

/// POST …/stylizer/pick (x, y, camera, time) and POST …/stylizer/constraints (the same, and
/// "colour": [r,g,b] in [0, 1], "alpha", "layer": the index of a diffusion layer (default: the
/// topmost, one is added when there is none), "anchor": "none" (default: the constraint keeps its
/// TF position) | "world" (it follows the point clicked) | "object" (it follows the occluder clicked)).
struct StylizerPickRequest {
    enum class Anchor { None, World, Object };
    int x = 0, y = 0;  ///< pixel, (0, 0) top left
    std::optional<core::Camera> camera;
    std::optional<double> time;
    Vec3d colour{1, 1, 1};
    double alpha = 1;
    std::optional<int> layer;
    Anchor anchor = Anchor::None;
    static StylizerPickRequest fromJson(const nlohmann::json& j, const RequestLimits& limits, bool constraint);
};

/// POST …/stylizer/sequence: {"fps": 24, "start": T, "end": T (default: the key frames' span;
/// required without keys), "video": true (also an MP4), "aov": NAME, "exposure": STOPS, "method",
/// "steps"}, all optional but as said.
struct StylizerSequenceRequest {
    double fps = 24;
    std::optional<double> start, end;
    bool video = false;
    core::StylizerOutput output = core::StylizerOutput::Frame;
    double exposure = 0;
    core::StylizeSettings settings;
    static StylizerSequenceRequest fromJson(const nlohmann::json& j);
};

/// The scene as JSON, every field written (defaults included), so that reading it back gives the
/// same scene: `meshRefs` name each occluder's mesh; `transferImageRef`, when given, is written
/// as `transfer_function.image` (an image TF of a file).
nlohmann::json stylizerSceneToJson(const core::StylizerScene& scene, const std::vector<std::string>& meshRefs,
                                   const std::optional<std::string>& transferImageRef = std::nullopt,
                                   const std::string& volumeSource = "session");

}  // namespace volstyle::protocol

#pragma once
/// \file render_json.h
/// JSON forms of the camera and the lighting (SPEC §1, §3), shared by the HTTP API and the CLI's
/// CAM.json / L.json files.
///
/// Camera: {"eye":[x,y,z], "target":[x,y,z], "up":[0,1,0], "fov_y_deg":40, "width":480,
///          "height":480, "near":0, "far":1e30}   (eye and target required)
/// Lighting: {"sun":{"direction":[x,y,z],"irradiance":[r,g,b]}, "lights":[{…}, …],
///            "background":[r,g,b] | {"color":[r,g,b]} | {"environment":"sky.exr"},
///            "phase":{"type":"isotropic"} | {"type":"henyey_greenstein","g":0.3},
///            "environment":{"lobes":16, "domain":"sphere"|"upper_hemisphere", "radiance":[[r,g,b], …],
///                           "map":"sky.exr", "strength":1, "light_volume_resolution":64}}
/// `sun` and `lights` together give at most 4 lights; no `sun` and no `lights` means no light.
/// `environment` lights the medium through `lobes` directional lobes (SPEC §8, docs/LIGHTING.md):
/// their radiances given, or fitted to `map` (a file path: the CLI only).

#include <nlohmann/json.hpp>

#include <optional>
#include <string>

#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/translucent/translucent_settings.h"
#include "core/volume/glass_sphere.h"
#include "protocol/validation.h"

namespace volstyle::protocol {

/// Throws ValidationError listing every invalid field (paths below `path`).
core::Camera cameraFromJson(const nlohmann::json& j, const std::string& path = "");
nlohmann::json cameraToJson(const core::Camera& camera);

struct LightingRequest {
    core::Lighting lighting;
    /// `background.environment`: an image path. Only the CLI accepts it (relative to the JSON
    /// file); the API never takes server-side paths.
    std::optional<std::string> environmentPath;
    /// `environment.map`: the same, for the map the environment light is fitted to.
    std::optional<std::string> environmentLightPath;
    /// Over the API, both name the session's uploaded map instead: the string "session"
    /// (PUT /sessions/{sid}/environment). resolve() puts the map in.
    bool backgroundUsesSessionMap = false;
    bool environmentUsesSessionMap = false;

    bool usesSessionMap() const { return backgroundUsesSessionMap || environmentUsesSessionMap; }
    /// The lighting with the session's map where it is named (the map wins over a radiance given
    /// beside it). Throws ValidationError naming the field when it is named and `sessionMap` is null.
    core::Lighting resolve(const std::shared_ptr<const core::Image>& sessionMap, const std::string& path = "") const;
};

/// The name by which lighting JSON refers to a session's uploaded environment map.
inline constexpr const char* kSessionMap = "session";
/// `"background": {"environment": "lobes"}`: the environment light's lobes are the background.
inline constexpr const char* kLobesBackground = "lobes";

/// The translucent preview's parameters (SPEC §9): {"slice_spacing", "light_buffer",
/// "indirect": {"enabled", "blur_angle_deg", "extinction", "transport_color"}, "surface_shading"};
/// absent fields keep their defaults. Throws ValidationError naming every bad field under `path`.
core::TranslucentSettings translucentFromJson(const nlohmann::json& j, const std::string& path = "");
nlohmann::json translucentToJson(const core::TranslucentSettings& s);
/// POST /sessions/{sid}/perturb: {"amplitude", "frequency", "octaves", "property_amplitude",
/// "seed", "time"} (core/translucent/perturbation.h), baked into a new version; one that changes
/// nothing (both amplitudes 0, an empty body) is refused.
core::Perturbation perturbationFromJson(const nlohmann::json& j);
/// POST …/refraction's body: a glass sphere (issue #16) — index, radius, edge_voxels, noise,
/// noise_frequency, seed; absent fields keep core::GlassSphere's defaults.
core::GlassSphere glassSphereFromJson(const nlohmann::json& j);

LightingRequest lightingFromJson(const nlohmann::json& j, const std::string& path = "",
                                 bool allowFilePaths = false);
/// The lighting as JSON; a map that is `sessionMap` is written as "session" (a map from a file is
/// not written: the background as its colour, the environment light as its projected radiances).
nlohmann::json lightingToJson(const core::Lighting& lighting, const core::Image* sessionMap = nullptr);

}  // namespace volstyle::protocol

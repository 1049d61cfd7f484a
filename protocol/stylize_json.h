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
///    "camera": {…SPEC §1…}, "background": [r,g,b], "time": 0}
/// Meshes are references the caller resolves (the CLI: paths relative to the file). Fields of
/// SPEC §7 that are not rendered yet (dilation, holes, volume, spot lights) are
/// refused by name rather than ignored.

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "core/stylize/scene.h"
#include "protocol/validation.h"

namespace volstyle::protocol {

struct StylizerSceneRequest {
    core::StylizerScene scene;          ///< occluders with empty meshes, in file order
    std::vector<std::string> meshRefs;  ///< each occluder's `mesh`
    /// `transfer_function.image` when there is one: scene.transferFunction is then set, its image
    /// left for the caller to load.
    std::optional<std::string> transferImageRef;
};

/// Throws ValidationError listing every invalid field (paths below `path`).
StylizerSceneRequest stylizerSceneFromJson(const nlohmann::json& j, const std::string& path = "");

}  // namespace volstyle::protocol

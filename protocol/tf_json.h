#pragma once
/// \file tf_json.h
/// A transfer function as JSON (SPEC §7, issue #15): an uploaded image, or a stack of layers
///   {"mode": "multiply"|"replace", "depth_range": [0, 50], "size": [128, 128],
///    "layers": [{"type": "solid", "colour": [r,g,b], "alpha": 1, "blend": "normal", "opacity": 1},
///               {"type": "gradient", "from": {CONSTRAINT}, "to": {CONSTRAINT}},
///               {"type": "image"},                      // the API: the image PUT to …/stylizer/tf
///               {"type": "diffusion", "constraints": [{"v_bar": 0.5, "depth": 0.2, "colour": [r,g,b],
///                 "alpha": 1, "anchor": {"position": [x,y,z], "follow": "trees"}}]}]}
/// blend: normal | multiply | add. A file's image layer (and a file's image TF) names its image
/// with "image": "tf.png"; the API takes no paths.

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "core/stylize/scene.h"
#include "protocol/validation.h"

namespace volstyle::protocol {

/// Where a scene comes from: a SCENE.json file (images are paths) or the API (no file paths: an
/// image TF or image layer uses the image uploaded to …/stylizer/tf).
enum class SceneSource { File, Api };

/// The images a parsed TF names, for the caller to load: the TF's own (`layer` −1) or an image
/// layer's. In the API the reference is empty (the uploaded image).
struct TfImageRef {
    int layer = -1;
    std::string ref;
    int key = -1;  ///< the TF of key frame `key`; −1: the scene's own
};

/// Records every problem below `path`; the images are left for the caller (`refs`).
core::TransferFunction transferFunctionFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path, SceneSource source,
                                                std::vector<TfImageRef>& refs);

/// Every field written, so that reading it back gives the same TF; `imageRef` names a file TF's
/// image (the API leaves it out).
nlohmann::json transferFunctionToJson(const core::TransferFunction& tf, const std::optional<std::string>& imageRef = std::nullopt);

/// One layer, and a constraint (with its anchor), as above.
nlohmann::json tfLayerToJson(const core::TfLayer& layer);
nlohmann::json tfConstraintToJson(const core::TfConstraint& c);

}  // namespace volstyle::protocol

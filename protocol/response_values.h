#pragma once
/// \file response_values.h
/// What the API answers about sessions, views, frames and the stylizer's uploads and picks, as
/// values (issue #36: the services return these, the HTTP routes encode them with
/// response_json.h; no JSON in between).

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/image/image.h"
#include "core/math/vec.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/stylize/tf_layers.h"

namespace volstyle::protocol {

/// A view: its camera and which images it has (GET …/views/{vid}).
struct ViewInfo {
    std::string id;
    core::Camera camera;
    bool hasTarget = false, hasWeights = false, hasBackground = false;
    std::optional<int> frame;  ///< the animation's frame it shows; none: the session's volume
    size_t clippedPixels = 0;  ///< target pixels left out as clipped (clip-aware upload)
};

struct EnvironmentMapInfo {
    int width = 0, height = 0;
    bool used = false;  ///< the lighting names it (background or environment light)
};

/// A session (GET /sessions/{sid}).
struct SessionInfo {
    std::string id, created, scene;
    Int3 dims;
    Vec3d lo, hi, voxelSize;
    std::vector<std::string> grids;  ///< extinction, albedo, emission, refractive_index
    bool sparse = false;             ///< stored as 8³ bricks (issue #39)
    int64_t activeVoxels = 0;        ///< voxels of the active bricks in the box (dense: the box)
    int64_t bytes = 0;               ///< what its grids take in memory
    int version = 1;
    int shows = 1;             ///< the version whose content the current one is (after an undo, redo or revert)
    int undo = 0, redo = 0;    ///< steps POST …/undo and …/redo can take
    core::Lighting lighting;
    std::shared_ptr<const core::Image> environmentMap;  ///< what the lighting calls "session"
    std::vector<ViewInfo> views;
    std::vector<std::string> jobs;
    std::vector<int> versions;
    std::vector<std::pair<std::string, std::string>> damaged;  ///< file, reason
    std::optional<EnvironmentMapInfo> environmentMapInfo;
};

/// A frame of the session's animation (GET …/frames).
struct FrameInfo {
    int frame = 0;
    Int3 dims;
    bool sparse = false;      ///< stored as bricks (issue #39)
    size_t activeVoxels = 0;  ///< voxels that hold data (dense: the box's)
    bool solved = false;
    int views = 0;  ///< views of this frame
};

struct OccluderMeshInfo {
    std::string name, format;
    size_t vertices = 0, triangles = 0, fileBytes = 0;
    Vec3 boundsLo, boundsHi;  ///< in the mesh's own space
    bool used = false;        ///< the scene's occluders use it
};

struct TransferImageInfo {
    int width = 0, height = 0, channels = 0;
    bool used = false;  ///< the scene has a transfer_function
};

/// What a click at a pixel of the stylizer's frame finds (POST …/stylizer/pick): the pixel's TF
/// position (V̄ and linear depth d), its distance, the occluder seen there and the point.
struct StylizerPick {
    int x = 0, y = 0;
    double vBar = 0, depth = 0, distance = 0;
    int occluder = -1;         ///< index in the scene; −1: the sky (no surface)
    std::string occluderName;  ///< empty for the sky
    Vec3d position;            ///< the world point at `distance` along the pixel's ray
    core::TfAnchor anchor;     ///< what the request's `anchor` asked for (position empty for "none")
    /// The TF a constraint there goes into: on a path whose keys carry TFs, the key nearest the
    /// time (its depth range gives `depth`); −1: the scene's own.
    int key = -1;
};

/// A constraint clicked into the scene (POST …/stylizer/constraints).
struct AddedTfConstraint {
    StylizerPick pick;
    int layer = 0, index = 0;  ///< where it went: transfer_function/layers/{layer}/constraints/{index}
    int key = -1;              ///< … of key frame `key` (on a path whose keys carry TFs); −1: the scene's TF
    core::TfConstraint constraint;
    uint64_t revision = 0;
};

}  // namespace volstyle::protocol

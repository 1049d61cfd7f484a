#pragma once
/// \file stylizer_record.h
/// A session's stylizer on disk (DIR/sessions/<sid>/stylizer/): scene.json (format 1: the scene
/// and its revision), history.json (the undo and redo stacks, written only when they change),
/// occluders/NAME.EXT and tf.image (uploads as they were sent). Read back with every upload
/// parsed again as untrusted; what a damaged file held is lost, and only that.

#include <filesystem>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/stylize/mesh.h"
#include "server/state/session_store.h"
#include "server/store/data_dir.h"

namespace volstyle::server::store {

/// The scene record: {"format", "revision", "scene"} with the scene as `scene` JSON.
std::string encodeStylizerScene(const nlohmann::json& scene, uint64_t revision);
/// The undo and redo stacks: each entry's scene as the scene record writes it.
std::string encodeStylizerHistory(const std::vector<StylizerSceneEntry>& undo, const std::vector<StylizerSceneEntry>& redo);

using MeshReader = std::function<core::Mesh(const std::string& bytes, const std::string& format)>;

/// Restores `s.stylizer` from `folder`/stylizer: uploads (meshes through `readMesh`; empty: in this
/// process), history and scene. A damaged file is quarantined and recorded in `s.damaged`: an
/// occluder whose mesh is gone is dropped, a transfer function whose image is gone is dropped, an
/// unreadable scene is builtin:forest again. When the scene lost something it is written back
/// (`saveScene(scene JSON, revision)`).
void restoreStylizerRecord(DataDir& dir, Session& s, const std::filesystem::path& folder, const MeshReader& readMesh,
                           const std::function<void(const nlohmann::json& scene, uint64_t revision)>& saveScene);

}  // namespace volstyle::server::store

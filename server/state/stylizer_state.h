#pragma once
/// \file stylizer_state.h
/// A session's light-shaft stylizer (SPEC §7 "API"): the scene with its meshes resolved, the
/// occluder meshes and the transfer-function image uploaded to it, a revision that counts every
/// change (the live stream renders each revision once), and the newest live frame. Every session
/// has one, opened on builtin:forest. Guarded by the session's mutex.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/stylize/scene.h"
#include "protocol/stylize_json.h"

namespace volstyle::server {

/// An occluder mesh uploaded to PUT …/stylizer/occluders/{name}.
struct UploadedMesh {
    std::string format;  ///< obj, ply, gltf or glb: the stored file's extension
    std::shared_ptr<const core::Mesh> mesh;
    size_t fileBytes = 0;
};

/// A frame of the live stream, encoded, with the revision it shows.
/// The live stream's JPEG quality: on a small forest frame, mean 3.2 and largest 20 levels from the
/// PNG (85: 4.3 and 33), at about 1 ms a 960×540 frame.
constexpr int kLiveJpegQuality = 90;

struct LiveFrame {
    uint64_t revision = 0;
    std::string bytes;  ///< JPEG
    int width = 0, height = 0;
    double renderMs = 0;  ///< the frame on the GL thread: render and read-back
    double encodeMs = 0;  ///< its JPEG
};

/// A scene kept for undo or redo: the core value (its meshes and images shared, not copied), the
/// mesh references as the client wrote them, and its size as the store writes it (the stacks'
/// byte bound).
struct StylizerSceneEntry {
    core::StylizerScene scene;
    std::vector<std::string> meshRefs;
    size_t bytes = 0;
};

struct StylizerState {
    core::StylizerScene scene;          ///< what frames render: meshes and the TF image attached
    std::vector<std::string> meshRefs;  ///< each occluder's `mesh`, as the client wrote it
    std::map<std::string, UploadedMesh> meshes;
    std::shared_ptr<const core::Image> transferImage;  ///< PUT …/stylizer/tf; null: none
    uint64_t revision = 1;
    LiveFrame live;  ///< revision 0: none yet
    /// Earlier scenes (oldest first) for POST …/stylizer/undo, and the ones undone for …/redo; a
    /// new scene clears the redo stack. At most kStylizerUndoDepth each, and kStylizerUndoBytes.
    std::vector<StylizerSceneEntry> undo, redo;

    /// Whether the scene's occluders use the uploaded mesh `name` (it cannot be deleted then).
    bool uses(const std::string& name) const;
    /// Whether the scene's TF shows the uploaded TF image (an image TF or an image layer).
    bool usesTransferImage() const;

    /// Vertices of every uploaded mesh together (bounded per session).
    size_t uploadedVertices() const;
};

inline constexpr size_t kStylizerUndoDepth = 64;
inline constexpr size_t kStylizerUndoBytes = size_t(4) << 20;  ///< each stack's scenes as written, at most (the newest always kept)

/// The least stylizer speed a frame's budget estimate assumes, in lookups per second: the device
/// is measured when its stylizer first starts (core::Stylizer::measureLookupsPerSecond; llvmpipe
/// on two cores measures ~1e8), and a measurement taken on a machine busy at that moment should
/// not refuse every frame.
inline constexpr double kMinStylizerLookupsPerSecond = 2.0e7;

/// The stylizer of a new session: builtin:forest (its meshes built once and shared).
StylizerState defaultStylizer();

/// Puts a new uploaded TF image into `scene`'s TFs where they show it (compiling their layers again).
void attachTransferImage(core::StylizerScene& scene, const std::shared_ptr<const core::Image>& image);

/// An undo entry of `scene`: without what can be made again (layered TFs' compiled images), so an entry holds little beyond its JSON's `bytes`.
StylizerSceneEntry sceneEntry(core::StylizerScene scene, std::vector<std::string> meshRefs, size_t bytes);
/// An undo entry of the state's scene now (its size measured by its JSON, as the store writes it).
StylizerSceneEntry currentSceneEntry(const StylizerState& state);

/// An undo entry made current again: its meshes looked up by reference among the uploads (a mesh
/// uploaded again under its name is the new one) and the built-in ones, its TF image the uploaded
/// one. Throws InvalidArgument naming what is gone (a deleted mesh, the TF image).
core::StylizerScene resolveSceneEntry(const StylizerState& state, const StylizerSceneEntry& entry);

/// Whether two scenes differ only in their time (scrubbing, playing: not a step to undo).
bool sameSceneApartFromTime(core::StylizerScene a, const core::StylizerScene& b);

/// Whether `name` may name an uploaded mesh: 1–64 of A–Z a–z 0–9 _ . - (it is a file name on disk).
bool isMeshName(const std::string& name);

/// The scene `request` describes, its meshes looked up in `state`'s uploads and the built-in ones
/// and its transfer function given the uploaded image and compiled when it is layers. Throws
/// protocol::ValidationError naming /occluders/i/mesh (no such mesh), /transfer_function (no image
/// uploaded) and the problems of the TF's layers.
/// `sessionVolume` gives a heterogeneous medium without a box the volume's bounds (no volume: the
/// box is required).
core::StylizerScene resolveStylizerScene(const StylizerState& state, const protocol::StylizerSceneRequest& request,
                                         const core::Volume* sessionVolume = nullptr);

}  // namespace volstyle::server

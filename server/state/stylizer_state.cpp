#include "server/state/stylizer_state.h"

#include <algorithm>
#include <tuple>

#include "core/base/errors.h"
#include "core/stylize/tf_anchors.h"

namespace volstyle::server {

bool StylizerState::uses(const std::string& name) const { return std::find(meshRefs.begin(), meshRefs.end(), name) != meshRefs.end(); }

size_t StylizerState::uploadedVertices() const {
    size_t n = 0;
    for (const auto& [name, m] : meshes) n += m.mesh->positions.size();
    return n;
}

namespace {

bool showsImage(const core::TransferFunction& tf) {
    return tf.layers.empty() ||
           std::any_of(tf.layers.begin(), tf.layers.end(), [](const core::TfLayer& l) { return l.kind == core::TfLayerKind::Image; });
}

}  // namespace

bool StylizerState::usesTransferImage() const {
    const auto tfs = scene.transferFunctions();
    return std::any_of(tfs.begin(), tfs.end(), [](const core::TransferFunction* tf) { return showsImage(*tf); });
}

void attachTransferImage(core::StylizerScene& scene, const std::shared_ptr<const core::Image>& image) {
    for (core::TransferFunction* tf : scene.transferFunctions()) {
        if (tf->layers.empty()) {
            tf->image = image;
            continue;
        }
        bool shown = false;
        for (core::TfLayer& l : tf->layers)
            if (l.kind == core::TfLayerKind::Image) l.image = image, shown = true;
        if (shown) core::compileTransferFunction(*tf);
    }
}

StylizerState defaultStylizer() {
    static const core::StylizerScene forest = [] {
        core::StylizerScene scene = core::builtinForest();
        for (core::Occluder& o : scene.occluders) o.mesh = protocol::builtinMesh(protocol::kBuiltinMeshPrefix + o.name);  // one copy
        return scene;
    }();
    StylizerState s;
    s.scene = forest;
    for (const core::Occluder& o : forest.occluders) s.meshRefs.push_back(protocol::kBuiltinMeshPrefix + o.name);
    return s;
}

StylizerSceneEntry sceneEntry(core::StylizerScene scene, std::vector<std::string> meshRefs, size_t bytes) {
    // What can be made again is not kept: the images layered TFs compile to (up to 1024² × 16 bytes each, per
    // TF and key: 64 entries of those would hold gigabytes).
    for (core::TransferFunction* tf : scene.transferFunctions())
        if (!tf->layers.empty()) tf->image.reset();
    return {std::move(scene), std::move(meshRefs), bytes};
}

StylizerSceneEntry currentSceneEntry(const StylizerState& state) {
    return sceneEntry(state.scene, state.meshRefs, protocol::stylizerSceneToJson(state.scene, state.meshRefs).dump().size());
}

core::StylizerScene resolveSceneEntry(const StylizerState& state, const StylizerSceneEntry& entry) {
    core::StylizerScene scene = entry.scene;
    for (size_t i = 0; i < entry.meshRefs.size() && i < scene.occluders.size(); ++i) {
        const std::string& ref = entry.meshRefs[i];
        if (auto builtin = protocol::builtinMesh(ref)) scene.occluders[i].mesh = builtin;
        else if (auto it = state.meshes.find(ref); it != state.meshes.end()) scene.occluders[i].mesh = it->second.mesh;
        else throw InvalidArgument("its occluder mesh '" + ref + "' was deleted");
    }
    const auto tfs = scene.transferFunctions();
    const bool usesImage = std::any_of(tfs.begin(), tfs.end(), [](const core::TransferFunction* tf) { return showsImage(*tf); });
    if (usesImage && !state.transferImage) throw InvalidArgument("its transfer-function image was deleted");
    if (usesImage) attachTransferImage(scene, state.transferImage);
    for (core::TransferFunction* tf : scene.transferFunctions())
        if (!tf->layers.empty() && !tf->image) core::compileTransferFunction(*tf);  // sceneEntry dropped it
    return scene;
}

bool sameSceneApartFromTime(core::StylizerScene a, const core::StylizerScene& b) {
    a.time = b.time;
    return a == b;
}

bool isMeshName(const std::string& name) {
    if (name.empty() || name.size() > 64 || name == "." || name == "..") return false;
    return std::all_of(name.begin(), name.end(), [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
    });
}

core::StylizerScene resolveStylizerScene(const StylizerState& state, const protocol::StylizerSceneRequest& request,
                                         const core::Volume* sessionVolume) {
    core::StylizerScene scene = request.scene;
    std::vector<protocol::FieldError> problems;
    for (size_t i = 0; i < request.meshRefs.size(); ++i) {
        const std::string& ref = request.meshRefs[i];
        const std::string path = "/occluders/" + std::to_string(i) + "/mesh";
        if (ref.rfind(protocol::kBuiltinMeshPrefix, 0) == 0) {
            scene.occluders[i].mesh = protocol::builtinMesh(ref);
            if (!scene.occluders[i].mesh) problems.push_back({path, "no built-in mesh '" + ref + "' (there are builtin:forest/ground and builtin:forest/trees)"});
        } else if (auto it = state.meshes.find(ref); it != state.meshes.end()) {
            scene.occluders[i].mesh = it->second.mesh;
        } else {
            problems.push_back({path, "no occluder mesh '" + ref + "' in this session: upload it first (PUT …/stylizer/occluders/" +
                                          (isMeshName(ref) ? ref : "NAME") + ") or use builtin:forest/trees"});
        }
    }
    for (const protocol::TfImageRef& ref : request.tfImages) {
        if (state.transferImage) protocol::attachTfImage(scene, ref, state.transferImage);
        else problems.push_back({(ref.key < 0 ? "" : "/keyframes/" + std::to_string(ref.key)) + "/transfer_function" +
                                     (ref.layer < 0 ? "" : "/layers/" + std::to_string(ref.layer)),
                                 "no transfer-function image uploaded: PUT it to …/stylizer/tf first"});
    }
    if (scene.volume && !request.volumeBoxGiven) {
        if (sessionVolume) std::tie(scene.volume->lo, scene.volume->hi) = sessionVolume->worldBounds();
        else problems.push_back({"/volume/box", "is required here (there is no volume whose bounds it could take)"});
    }
    if (!problems.empty()) throw protocol::ValidationError(problems);
    try {
        scene.checkTfCompileWork();  // before the work, not after it
    } catch (const InvalidArgument& e) {
        throw protocol::ValidationError(std::vector<protocol::FieldError>{{"/transfer_function", e.what()}});
    }
    for (core::TransferFunction* tf : scene.transferFunctions()) try {
            core::compileTransferFunction(*tf);  // anchored ones again for each frame
        } catch (const InvalidArgument& e) {
            throw protocol::ValidationError(std::vector<protocol::FieldError>{{"/transfer_function/layers", e.what()}});
        }
    return scene;
}

}  // namespace volstyle::server

#include "server/store/stylizer_record.h"

#include <spdlog/spdlog.h>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/stylize/mesh_io.h"
#include "protocol/stylize_json.h"
#include "protocol/validation.h"

namespace volstyle::server::store {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string encodeStylizerScene(const json& scene, uint64_t revision) {
    return protocol::toText({{"format", 1}, {"revision", revision}, {"scene", scene}}, 2);
}

std::string encodeStylizerHistory(const std::vector<StylizerSceneEntry>& undo, const std::vector<StylizerSceneEntry>& redo) {
    const auto stack = [](const std::vector<StylizerSceneEntry>& entries) {
        json out = json::array();
        for (const auto& e : entries) out.push_back(protocol::stylizerSceneToJson(e.scene, e.meshRefs));
        return out;
    };
    return protocol::toText({{"undo", stack(undo)}, {"redo", stack(redo)}});
}

namespace {

/// An undo entry read back, as it was written: its meshes, TF image and compiled TFs are found
/// when an undo makes it current again (resolveSceneEntry), so a restart compiles nothing here,
/// and a step whose mesh was deleted is dropped then, as before the restart.
StylizerSceneEntry entryOf(const json& scene) {
    protocol::StylizerSceneRequest request = protocol::stylizerSceneFromJson(scene, "", protocol::SceneSource::Api);
    return sceneEntry(std::move(request.scene), std::move(request.meshRefs), scene.dump().size());
}

}  // namespace

namespace {

/// A file found damaged: quarantined, and listed in the session's damage.
void damage(DataDir& data, Session& s, const std::string& file, const std::string& reason) {
    data.quarantineFile(s.id, file, reason);
    s.damaged.push_back({file, reason});
}

/// The uploads: occluder meshes (each read again as untrusted) and the TF image.
void restoreUploads(DataDir& data, Session& s, const fs::path& dir, const MeshReader& readMesh) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(dir / "stylizer" / "occluders", ec)) {
        const std::string file = "stylizer/occluders/" + entry.path().filename().string();
        const std::string format = entry.path().extension().string().substr(entry.path().extension().empty() ? 0 : 1);
        if (isUnfinishedWrite(entry.path())) continue;  // an unfinished write (atomicWrite's temporary)
        try {
            const std::string bytes = readFile(entry.path());
            auto mesh = std::make_shared<const core::Mesh>(readMesh ? readMesh(bytes, format) : core::loadMeshFromMemory(bytes, format));
            s.stylizer.meshes[entry.path().stem().string()] = {format, std::move(mesh), bytes.size()};
        } catch (const std::exception& e) {
            damage(data, s, file, e.what());
        }
    }
    if (!fs::exists(dir / "stylizer" / "tf.image")) return;
    try {
        const std::string bytes = readFile(dir / "stylizer" / "tf.image");
        s.stylizer.transferImage =
            std::make_shared<const core::Image>(core::loadImageFromMemory(bytes.data(), bytes.size(), "the transfer function", 4096).image);
    } catch (const std::exception& e) {
        damage(data, s, "stylizer/tf.image", e.what());
    }
}

/// The undo and redo stacks: a convenience, so an unreadable file is dropped, not the scene (and
/// a step that no longer reads, alone).
void restoreHistory(Session& s, const fs::path& dir) {
    if (!fs::exists(dir / "stylizer" / "history.json")) return;
    try {
        const json h = json::parse(readFile(dir / "stylizer" / "history.json"));
        for (auto [stack, name] : {std::pair{&s.stylizer.undo, "undo"}, std::pair{&s.stylizer.redo, "redo"}})
            for (const json& scene : h.at(name)) try {
                    stack->push_back(entryOf(scene));
                } catch (const std::exception& e) {
                    spdlog::info("session {}: a stylizer {} step does not read and was dropped: {}", s.id, name, e.what());
                }
    } catch (const std::exception& e) {
        s.stylizer.undo.clear(), s.stylizer.redo.clear();
        spdlog::warn("session {}: the stylizer's undo history is unreadable and was dropped: {}", s.id, e.what());
    }
}

/// Drops from `request` what damaged uploads held — occluders whose mesh is gone, the TFs that
/// showed a lost TF image — and says what went.
std::vector<std::string> dropLostUploads(const Session& s, protocol::StylizerSceneRequest& request) {
    std::vector<std::string> lost;
    for (size_t i = request.meshRefs.size(); i-- > 0;)
        if (!protocol::builtinMesh(request.meshRefs[i]) && !s.stylizer.meshes.contains(request.meshRefs[i])) {
            lost.push_back("occluder '" + request.scene.occluders[i].name + "' (mesh '" + request.meshRefs[i] + "')");
            request.meshRefs.erase(request.meshRefs.begin() + std::ptrdiff_t(i));
            request.scene.occluders.erase(request.scene.occluders.begin() + std::ptrdiff_t(i));
        }
    if (!request.tfImages.empty() && !s.stylizer.transferImage) {
        bool scene = false, keys = false;
        for (const auto& ref : request.tfImages) (ref.key < 0 ? scene : keys) = true;
        if (scene) lost.push_back("the transfer function"), request.scene.transferFunction.reset();
        if (keys) {
            lost.push_back("the key frames' transfer functions");
            for (auto& k : request.scene.keyframes) k.transferFunction.reset();
        }
        request.tfImages.clear();
    }
    return lost;
}

}  // namespace

void restoreStylizerRecord(DataDir& data, Session& s, const fs::path& dir, const MeshReader& readMesh,
                           const std::function<void(const json& scene, uint64_t revision)>& saveScene) {
    restoreUploads(data, s, dir, readMesh);
    restoreHistory(s, dir);
    if (!fs::exists(dir / "stylizer" / "scene.json")) return;  // never edited: builtin:forest
    protocol::StylizerSceneRequest request;
    try {
        const json j = json::parse(readFile(dir / "stylizer" / "scene.json"));
        if (j.value("format", 1) > 1) throw IoError("its format " + j.at("format").dump() + " is newer than this server's (1)");
        request = protocol::stylizerSceneFromJson(j.at("scene"), "", protocol::SceneSource::Api);
        s.stylizer.revision = j.at("revision").get<uint64_t>();
    } catch (const std::exception& e) {
        damage(data, s, "stylizer/scene.json", std::string("the stylizer's scene is unreadable (it is builtin:forest again): ") + e.what());
        return;
    }
    const std::vector<std::string> lost = dropLostUploads(s, request);  // what a damaged upload held, and only that
    try {
        s.stylizer.scene = resolveStylizerScene(s.stylizer, request);
        s.stylizer.meshRefs = request.meshRefs;
    } catch (const std::exception& e) {
        damage(data, s, "stylizer/scene.json", std::string("the stylizer's scene no longer loads (it is builtin:forest again): ") + e.what());
        return;
    }
    if (lost.empty()) return;
    std::string what;
    for (const auto& l : lost) what += (what.empty() ? "" : ", ") + l;
    s.damaged.push_back({"stylizer/scene.json", "its uploads were damaged; the scene lost " + what});
    spdlog::error("session {}'s stylizer scene lost {}", s.id, what);
    saveScene(protocol::stylizerSceneToJson(s.stylizer.scene, s.stylizer.meshRefs), ++s.stylizer.revision);
}

}  // namespace volstyle::server::store

// A session's stylizer uploads (SPEC §7 "API"): occluder meshes (parsed in the child reader) and
// the transfer-function image; each change moves the revision when the scene shows it.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/stylize/mesh_io.h"
#include "core/stylize/keyframes.h"
#include "core/stylize/stylizer.h"
#include "core/stylize/tf_anchors.h"
#include "server/runtime/mesh_reader.h"
#include "server/service/services.h"

namespace volstyle::server {
namespace {

std::string meshFile(const std::string& name, const std::string& format) { return "stylizer/occluders/" + name + "." + format; }
const std::string kTransferFile = "stylizer/tf.image";

OccluderMeshInfo meshInfo(const std::string& name, const UploadedMesh& m, const StylizerState& state) {
    auto [lo, hi] = m.mesh->bounds();
    return {name, m.format, m.mesh->positions.size(), m.mesh->triangleCount(), m.fileBytes, lo, hi, state.uses(name)};
}

}  // namespace

std::vector<OccluderMeshInfo> StylizerService::occluderMeshes(Session& s) const {
    std::lock_guard lock(s.mutex);
    std::vector<OccluderMeshInfo> out;
    for (const auto& [name, m] : s.stylizer.meshes) out.push_back(meshInfo(name, m, s.stylizer));
    return out;
}

OccluderMeshInfo StylizerService::putOccluderMesh(Session& s, const std::string& name, const std::string& bytes) {
    if (!isMeshName(name))
        throw ApiError(ErrorCode::InvalidArgument, "a mesh name is 1-64 characters of A-Z, a-z, 0-9, '_', '.' and '-'; got '" + name + "'");
    m_ctx.checkUploadSize(bytes, "the mesh");
    core::MeshLimits limits = m_ctx.limits.meshLimits;
    limits.maxFileBytes = std::min(limits.maxFileBytes, m_ctx.limits.maxUploadBytes);
    {
        std::lock_guard lock(s.mutex);  // before the parse: a full session refuses at once
        auto& meshes = s.stylizer.meshes;
        if (!meshes.contains(name) && meshes.size() >= m_ctx.limits.maxMeshesPerSession)
            throw ApiError(ErrorCode::TooLarge, "a session holds at most " + std::to_string(m_ctx.limits.maxMeshesPerSession) +
                                                    " occluder meshes; delete one first (DELETE …/stylizer/occluders/NAME)");
        const size_t others = s.stylizer.uploadedVertices() - (meshes.contains(name) ? meshes.at(name).mesh->positions.size() : 0);
        limits.maxVertices -= std::min(others, limits.maxVertices);  // what the session's other meshes leave
    }
    UploadedMesh uploaded{core::meshFormatOf(bytes), nullptr, bytes.size()};
    {
        ServiceContext::DecodeSlot slot(m_ctx.decodeSlots);
        try {
            uploaded.mesh = std::make_shared<const core::Mesh>(loadUntrustedMesh(bytes, uploaded.format, limits, m_ctx.limits.vdbReader));
        } catch (const LimitExceeded& e) {
            throw ApiError(ErrorCode::TooLarge, std::string(e.what()) +
                                                    (limits.maxVertices < m_ctx.limits.meshLimits.maxVertices
                                                         ? " (the session's other meshes hold " +
                                                               std::to_string(m_ctx.limits.meshLimits.maxVertices - limits.maxVertices) +
                                                               " of its " + std::to_string(m_ctx.limits.meshLimits.maxVertices) + " vertices)"
                                                         : std::string()));
        } catch (const Error& e) {
            throw ApiError(ErrorCode::UnsupportedMedia, e.what());  // corrupt, empty, not a mesh, non-finite
        }
    }
    std::lock_guard lock(s.mutex);
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    {
        const auto bytesOf = [](const core::Mesh& m) { return (m.positions.size() + m.normals.size()) * sizeof(Vec3) + m.indices.size() * sizeof(uint32_t); };
        const auto old = s.stylizer.meshes.find(name);
        m_ctx.memory.check(s, bytesOf(*uploaded.mesh), old != s.stylizer.meshes.end() && old->second.mesh ? bytesOf(*old->second.mesh) : 0,
                       "the mesh '" + name + "'");
    }
    if (m_ctx.persist) {
        if (auto old = s.stylizer.meshes.find(name); old != s.stylizer.meshes.end() && old->second.format != uploaded.format)
            m_ctx.persist->removeSessionFile(s.id, meshFile(name, old->second.format));
        m_ctx.persist->saveSessionFile(s.id, meshFile(name, uploaded.format), bytes);
    }
    s.stylizer.meshes[name] = uploaded;
    if (s.stylizer.uses(name)) {  // the scene shows the new mesh
        for (size_t i = 0; i < s.stylizer.meshRefs.size(); ++i)
            if (s.stylizer.meshRefs[i] == name) s.stylizer.scene.occluders[i].mesh = uploaded.mesh;
        m_ctx.stylizerChanged(s);
    }
    return meshInfo(name, uploaded, s.stylizer);
}

void StylizerService::removeOccluderMesh(Session& s, const std::string& name) {
    std::lock_guard lock(s.mutex);
    auto it = s.stylizer.meshes.find(name);
    if (it == s.stylizer.meshes.end()) throw ApiError(ErrorCode::NotFound, "no occluder mesh '" + name + "' in session '" + s.id + "'");
    if (s.stylizer.uses(name))
        throw ApiError(ErrorCode::Busy, "the stylizer's scene uses mesh '" + name + "'; PUT a scene without it first");
    if (m_ctx.persist) m_ctx.persist->removeSessionFile(s.id, meshFile(name, it->second.format));
    s.stylizer.meshes.erase(it);
}

TransferImageInfo StylizerService::setTransferImage(Session& s, const std::string& bytes) {
    m_ctx.checkUploadSize(bytes, "the transfer function");
    std::optional<ServiceContext::DecodeSlot> slot;
    core::LoadedImage loaded;
    try {
        loaded = core::loadImageFromMemory(bytes.data(), bytes.size(), "the transfer function", 4096,
                                           [&](int, int) { slot.emplace(m_ctx.decodeSlots); });
    } catch (const Error& e) {
        throw ApiError(ErrorCode::UnsupportedMedia, e.what());
    }
    if (loaded.channels < 3)
        throw ApiError(ErrorCode::UnsupportedMedia, "a transfer function is an RGB or RGBA image; this one has " +
                                                        std::to_string(loaded.channels) + " channel" + (loaded.channels == 1 ? "" : "s"));
    for (float v : loaded.image.rgba)
        if (v < 0) throw ApiError(ErrorCode::UnsupportedMedia, "the transfer function has negative values; they must be >= 0");
    auto image = std::make_shared<const core::Image>(std::move(loaded.image));
    std::lock_guard lock(s.mutex);
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    m_ctx.memory.check(s, image->rgba.size() * sizeof(float),
                   s.stylizer.transferImage ? s.stylizer.transferImage->rgba.size() * sizeof(float) : 0, "the transfer function");
    const bool used = s.stylizer.usesTransferImage();
    core::StylizerScene scene = s.stylizer.scene;
    if (used) {  // the scene must stay valid with it (key frames' TFs share a size)
        attachTransferImage(scene, image);
        try {
            scene.validate();
        } catch (const InvalidArgument& e) {
            throw ApiError(ErrorCode::Busy, std::string("the scene shows the TF image and would not be valid with this one: ") + e.what() +
                                                "; PUT a scene that does not show it first");
        }
    }
    if (m_ctx.persist) m_ctx.persist->saveSessionFile(s.id, kTransferFile, bytes);
    s.stylizer.transferImage = image;
    if (used) {
        s.stylizer.scene = std::move(scene);
        m_ctx.stylizerChanged(s);
    }
    return {image->width, image->height, loaded.channels, used};
}

core::Image StylizerService::transferImage(Session& s) const {
    std::lock_guard lock(s.mutex);
    if (!s.stylizer.transferImage) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' has no transfer function uploaded");
    return *s.stylizer.transferImage;
}

core::Image StylizerService::compiledTransferFunction(Session& s) const {
    std::lock_guard lock(s.mutex);
    const auto& tf = s.stylizer.scene.transferFunction;
    if (!tf || !tf->image) throw ApiError(ErrorCode::NotFound, "the stylizer's scene has no transfer function");
    return *tf->image;
}

void StylizerService::removeTransferImage(Session& s) {
    std::lock_guard lock(s.mutex);
    if (!s.stylizer.transferImage) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' has no transfer function uploaded");
    if (s.stylizer.usesTransferImage())
        throw ApiError(ErrorCode::Busy, "the stylizer's scene shows the transfer-function image; PUT a scene without it (no image TF, no image layer) first");
    if (m_ctx.persist) m_ctx.persist->removeSessionFile(s.id, kTransferFile);
    s.stylizer.transferImage.reset();
}

}  // namespace volstyle::server

// The stylizer of a session (SPEC §7 "API"): its scene, occluder meshes and transfer function,
// frames on the GL thread, and the live stream's frames.
#include <fmt/format.h>

#include <algorithm>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/stylize/mesh_io.h"
#include "core/stylize/keyframes.h"
#include "core/stylize/stylizer.h"
#include "core/stylize/tf_anchors.h"
#include "server/runtime/mesh_reader.h"
#include "server/service/session_service.h"

namespace volstyle::server {
namespace {

using protocol::ApiError;
using protocol::ErrorCode;

using Clock = std::chrono::steady_clock;

std::string meshFile(const std::string& name, const std::string& format) { return "stylizer/occluders/" + name + "." + format; }
const std::string kTransferFile = "stylizer/tf.image";

/// The scene a request renders: at its time (on a path: the path's camera there), then from its
/// camera when it names one.
core::StylizerScene sceneFor(const core::StylizerScene& scene, const std::optional<core::Camera>& camera, std::optional<double> time) {
    core::StylizerScene out = core::sceneAtTime(scene, time.value_or(scene.time));
    if (camera) out.camera = *camera;
    return out;
}

/// Pushes a scene onto an undo or redo stack, dropping the oldest beyond its depth or its bytes.
void remember(std::vector<StylizerSceneEntry>& stack, StylizerSceneEntry entry) {
    stack.push_back(std::move(entry));
    size_t bytes = 0;
    for (const auto& e : stack) bytes += e.bytes;
    while (stack.size() > 1 && (stack.size() > kStylizerUndoDepth || bytes > kStylizerUndoBytes)) {
        bytes -= stack.front().bytes;
        stack.erase(stack.begin());
    }
}

}  // namespace

namespace {

/// Gives a heterogeneous medium the session volume's σt grid (made once per version). The
/// session's lock held.
void attachDensity(Session& s, core::StylizerScene& scene) {
    if (!scene.volume) return;
    if (!s.stylizer.density || s.stylizer.densityVersion != s.version) {
        s.stylizer.density = core::densityGridOf(s.volume);
        s.stylizer.densityVersion = s.version;
    }
    scene.volume->grid = s.stylizer.density;
}

/// The stylizer's state as a render reads it: the scene (with the session's current volume), its
/// mesh references and revision. The session's lock held.
StylizerSnapshot snapshotOf(Session& s) {
    StylizerSnapshot out{s.stylizer.scene, s.stylizer.meshRefs, s.stylizer.revision};
    attachDensity(s, out.scene);
    return out;
}

}  // namespace

StylizerSnapshot SessionService::stylizer(Session& s) const {
    std::lock_guard lock(s.mutex);
    return snapshotOf(s);
}

void SessionService::stylizerChanged(Session& s, bool history) {
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    if (m_persist) {
        if (history) m_persist->saveStylizerHistory(s.id, s.stylizer.undo, s.stylizer.redo);
        m_persist->saveStylizerScene(s.id, protocol::stylizerSceneToJson(s.stylizer.scene, s.stylizer.meshRefs), s.stylizer.revision + 1);
    }
    ++s.stylizer.revision;
    s.stylizerChanged.notify_all();
}

void SessionService::checkStylizerCameras(const core::StylizerScene& scene) const {
    auto checkSize = [&](const core::Camera& camera, const std::string& path) {
        for (auto [side, name] : {std::pair{camera.width, "width"}, std::pair{camera.height, "height"}})
            if (side > m_limits.maxImageSide) {
                const std::string message = "images are limited to " + std::to_string(m_limits.maxImageSide) + " pixels a side";
                throw ApiError(ErrorCode::TooLarge, message, {{path + "/" + name, message}});
            }
    };
    checkSize(scene.camera, "/camera");
    for (size_t k = 0; k < scene.keyframes.size(); ++k) checkSize(scene.keyframes[k].camera, "/keyframes/" + std::to_string(k) + "/camera");
}

StylizerSnapshot SessionService::commitStylizerScene(Session& s, core::StylizerScene scene, std::vector<std::string> meshRefs) {
    attachDensity(s, scene);
    try {
        scene.validate();
    } catch (const InvalidArgument& e) {
        throw ApiError(ErrorCode::InvalidArgument, e.what());
    }
    // A change of time alone (scrubbing, playing) or none at all is not a step to undo.
    nlohmann::json before = protocol::stylizerSceneToJson(s.stylizer.scene, s.stylizer.meshRefs);
    nlohmann::json after = protocol::stylizerSceneToJson(scene, meshRefs);
    before.erase("time"), after.erase("time");
    const bool step = before != after;
    if (step) {
        remember(s.stylizer.undo, currentSceneEntry(s.stylizer));
        s.stylizer.redo.clear();
    }
    s.stylizer.scene = std::move(scene);
    s.stylizer.meshRefs = std::move(meshRefs);
    stylizerChanged(s, step);
    return snapshotOf(s);
}

StylizerSnapshot SessionService::setStylizerScene(Session& s, const protocol::StylizerSceneRequest& request) {
    checkStylizerCameras(request.scene);
    std::lock_guard lock(s.mutex);
    return commitStylizerScene(s, resolveStylizerScene(s.stylizer, request, &s.volume), request.meshRefs);
}

StylizerSnapshot SessionService::undoStylizer(Session& s, bool redo) {
    std::lock_guard lock(s.mutex);
    auto& from = redo ? s.stylizer.redo : s.stylizer.undo;
    auto& to = redo ? s.stylizer.undo : s.stylizer.redo;
    if (from.empty()) throw ApiError(ErrorCode::Busy, redo ? "nothing to redo" : "nothing to undo");
    core::StylizerScene scene;
    try {
        scene = resolveSceneEntry(s.stylizer, from.back());
        attachDensity(s, scene);
        scene.validate();
    } catch (const std::exception& e) {  // a mesh or the TF image it used was deleted since: dropped, the one before is next
        from.pop_back();
        throw ApiError(ErrorCode::Busy, std::string("the ") + (redo ? "next" : "previous") + " scene no longer resolves, so it was dropped (" +
                                            e.what() + "); try again for the one before it");
    }
    std::vector<std::string> meshRefs = from.back().meshRefs;
    remember(to, currentSceneEntry(s.stylizer));
    from.pop_back();
    s.stylizer.scene = std::move(scene);
    s.stylizer.meshRefs = std::move(meshRefs);
    stylizerChanged(s, true);
    return snapshotOf(s);
}

namespace {

OccluderMeshInfo meshInfo(const std::string& name, const UploadedMesh& m, const StylizerState& state) {
    auto [lo, hi] = m.mesh->bounds();
    return {name, m.format, m.mesh->positions.size(), m.mesh->triangleCount(), m.fileBytes, lo, hi, state.uses(name)};
}

}  // namespace

std::vector<OccluderMeshInfo> SessionService::occluderMeshes(Session& s) const {
    std::lock_guard lock(s.mutex);
    std::vector<OccluderMeshInfo> out;
    for (const auto& [name, m] : s.stylizer.meshes) out.push_back(meshInfo(name, m, s.stylizer));
    return out;
}

OccluderMeshInfo SessionService::putOccluderMesh(Session& s, const std::string& name, const std::string& bytes) {
    if (!isMeshName(name))
        throw ApiError(ErrorCode::InvalidArgument, "a mesh name is 1-64 characters of A-Z, a-z, 0-9, '_', '.' and '-'; got '" + name + "'");
    checkUploadSize(bytes, "the mesh");
    core::MeshLimits limits = m_limits.meshLimits;
    limits.maxFileBytes = std::min(limits.maxFileBytes, m_limits.maxUploadBytes);
    {
        std::lock_guard lock(s.mutex);  // before the parse: a full session refuses at once
        auto& meshes = s.stylizer.meshes;
        if (!meshes.contains(name) && meshes.size() >= m_limits.maxMeshesPerSession)
            throw ApiError(ErrorCode::TooLarge, "a session holds at most " + std::to_string(m_limits.maxMeshesPerSession) +
                                                    " occluder meshes; delete one first (DELETE …/stylizer/occluders/NAME)");
        const size_t others = s.stylizer.uploadedVertices() - (meshes.contains(name) ? meshes.at(name).mesh->positions.size() : 0);
        limits.maxVertices -= std::min(others, limits.maxVertices);  // what the session's other meshes leave
    }
    UploadedMesh uploaded{core::meshFormatOf(bytes), nullptr, bytes.size()};
    {
        DecodeSlot slot(m_decodeSlots);
        try {
            uploaded.mesh = std::make_shared<const core::Mesh>(loadUntrustedMesh(bytes, uploaded.format, limits, m_limits.vdbReader));
        } catch (const LimitExceeded& e) {
            throw ApiError(ErrorCode::TooLarge, std::string(e.what()) +
                                                    (limits.maxVertices < m_limits.meshLimits.maxVertices
                                                         ? " (the session's other meshes hold " +
                                                               std::to_string(m_limits.meshLimits.maxVertices - limits.maxVertices) +
                                                               " of its " + std::to_string(m_limits.meshLimits.maxVertices) + " vertices)"
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
        m_memory.check(s, bytesOf(*uploaded.mesh), old != s.stylizer.meshes.end() && old->second.mesh ? bytesOf(*old->second.mesh) : 0,
                       "the mesh '" + name + "'");
    }
    if (m_persist) {
        if (auto old = s.stylizer.meshes.find(name); old != s.stylizer.meshes.end() && old->second.format != uploaded.format)
            m_persist->removeSessionFile(s.id, meshFile(name, old->second.format));
        m_persist->saveSessionFile(s.id, meshFile(name, uploaded.format), bytes);
    }
    s.stylizer.meshes[name] = uploaded;
    if (s.stylizer.uses(name)) {  // the scene shows the new mesh
        for (size_t i = 0; i < s.stylizer.meshRefs.size(); ++i)
            if (s.stylizer.meshRefs[i] == name) s.stylizer.scene.occluders[i].mesh = uploaded.mesh;
        stylizerChanged(s);
    }
    return meshInfo(name, uploaded, s.stylizer);
}

void SessionService::removeOccluderMesh(Session& s, const std::string& name) {
    std::lock_guard lock(s.mutex);
    auto it = s.stylizer.meshes.find(name);
    if (it == s.stylizer.meshes.end()) throw ApiError(ErrorCode::NotFound, "no occluder mesh '" + name + "' in session '" + s.id + "'");
    if (s.stylizer.uses(name))
        throw ApiError(ErrorCode::Busy, "the stylizer's scene uses mesh '" + name + "'; PUT a scene without it first");
    if (m_persist) m_persist->removeSessionFile(s.id, meshFile(name, it->second.format));
    s.stylizer.meshes.erase(it);
}

TransferImageInfo SessionService::setTransferImage(Session& s, const std::string& bytes) {
    checkUploadSize(bytes, "the transfer function");
    std::optional<DecodeSlot> slot;
    core::LoadedImage loaded;
    try {
        loaded = core::loadImageFromMemory(bytes.data(), bytes.size(), "the transfer function", 4096,
                                           [&](int, int) { slot.emplace(m_decodeSlots); });
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
    m_memory.check(s, image->rgba.size() * sizeof(float),
                   s.stylizer.transferImage ? s.stylizer.transferImage->rgba.size() * sizeof(float) : 0, "the transfer function");
    const bool used = s.stylizer.usesTransferImage();
    core::StylizerScene scene = s.stylizer.scene;
    if (used) {  // the scene must stay valid with it (key frames' TFs share a size)
        attachTransferImage(scene, image);
        attachDensity(s, scene);
        try {
            scene.validate();
        } catch (const InvalidArgument& e) {
            throw ApiError(ErrorCode::Busy, std::string("the scene shows the TF image and would not be valid with this one: ") + e.what() +
                                                "; PUT a scene that does not show it first");
        }
    }
    if (m_persist) m_persist->saveSessionFile(s.id, kTransferFile, bytes);
    s.stylizer.transferImage = image;
    if (used) {
        s.stylizer.scene = std::move(scene);
        stylizerChanged(s);
    }
    return {image->width, image->height, loaded.channels, used};
}

core::Image SessionService::transferImage(Session& s) const {
    std::lock_guard lock(s.mutex);
    if (!s.stylizer.transferImage) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' has no transfer function uploaded");
    return *s.stylizer.transferImage;
}

core::Image SessionService::compiledTransferFunction(Session& s) const {
    std::lock_guard lock(s.mutex);
    const auto& tf = s.stylizer.scene.transferFunction;
    if (!tf || !tf->image) throw ApiError(ErrorCode::NotFound, "the stylizer's scene has no transfer function");
    return *tf->image;
}

void SessionService::removeTransferImage(Session& s) {
    std::lock_guard lock(s.mutex);
    if (!s.stylizer.transferImage) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' has no transfer function uploaded");
    if (s.stylizer.usesTransferImage())
        throw ApiError(ErrorCode::Busy, "the stylizer's scene shows the transfer-function image; PUT a scene without it (no image TF, no image layer) first");
    if (m_persist) m_persist->removeSessionFile(s.id, kTransferFile);
    s.stylizer.transferImage.reset();
}

core::Stylizer& SessionService::stylizerEngine(core::GpuDevice& device) {
    if (!m_stylizer) m_stylizer = std::make_unique<core::Stylizer>(device);
    return *m_stylizer;
}

core::StylizedFrame SessionService::stylizeOnGl(const core::StylizerScene& scene, const core::StylizeSettings& settings) {
    // Other sessions' frames and a solve's next iteration wait behind this one: estimate it first.
    const double seconds = stylizerSeconds(scene, settings);
    if (m_limits.renderBudgetSeconds > 0 && seconds > m_limits.renderBudgetSeconds)
        throw ApiError(ErrorCode::OverBudget,
                       fmt::format("this frame would take about {:.0f} s, over the render budget of {:g} s (volstyle serve --render-budget); "
                                   "use fewer pixels, {}a smaller shadow map or shorter dilations",
                                   seconds, m_limits.renderBudgetSeconds,
                                   settings.method == core::VisibilityMethod::Naive ? "fewer steps or the accelerated method, " : ""));
    return m_gl->run([&](core::GpuDevice& device) { return stylizerEngine(device).render(scene, settings); });
}

core::StylizedFrame SessionService::stylize(Session& s, const protocol::StylizerFrameRequest& request) {
    core::StylizerScene scene = sceneFor(stylizer(s).scene, request.camera, request.time);
    core::StylizeSettings settings = request.settings;
    core::readBackOnly(settings, request.output);
    return stylizeOnGl(scene, settings);
}

StylizerPick SessionService::pickStylizer(Session& s, const protocol::StylizerPickRequest& q) { return pickIn(stylizer(s).scene, q); }

StylizerPick SessionService::pickIn(const core::StylizerScene& sessionScene, const protocol::StylizerPickRequest& q) {
    const core::StylizerScene scene = sceneFor(sessionScene, q.camera, q.time);
    const core::Camera& cam = scene.camera;
    if (!(q.x >= 0 && q.y >= 0 && q.x < cam.width && q.y < cam.height)) {
        const std::string message = "the pixel must be inside the " + std::to_string(cam.width) + "×" + std::to_string(cam.height) + " frame";
        throw ApiError(ErrorCode::InvalidArgument, message, {{"/x", message}, {"/y", message}});
    }
    core::StylizeSettings settings;
    settings.readShadowMaps = false;
    settings.pick = core::StylizeSettings::Pixel{q.x, q.y};
    settings.pickOnly = true;  // the frame and its AOVs come back 1×1: the picked pixel at (0, 0)
    const core::StylizedFrame f = stylizeOnGl(scene, settings);
    StylizerPick pick;
    if (!scene.keyframes.empty() && scene.keyframes.front().transferFunction) {
        const core::PathPosition on = core::pathPosition(scene.keyframes, scene.time);
        pick.key = int(on.weight < 0.5 ? on.before : on.after);
    }
    const core::TransferFunction tf = pick.key >= 0 ? *scene.keyframes[size_t(pick.key)].transferFunction
                                                    : scene.transferFunction.value_or(core::TransferFunction{});
    const core::TfPosition at = core::tfPositionAt(tf, f, 0, 0);
    pick.x = q.x, pick.y = q.y;
    pick.vBar = at.vBar, pick.depth = at.depth;
    pick.distance = f.linearDepth.pixel(0, 0)[0];
    pick.occluder = f.pickedOccluder;
    if (pick.occluder >= 0) pick.occluderName = scene.occluders[size_t(pick.occluder)].name;
    pick.position = cam.eye + cam.rayDirection(q.x, q.y) * pick.distance;
    if (q.anchor == protocol::StylizerPickRequest::Anchor::Object && pick.occluder < 0)
        throw ApiError(ErrorCode::InvalidArgument, "no occluder at pixel (" + std::to_string(q.x) + ", " + std::to_string(q.y) +
                                                       ") to follow; click on one or anchor to the world",
                       {{"/anchor", "no occluder at this pixel"}});
    if (q.anchor == protocol::StylizerPickRequest::Anchor::Object && pick.occluderName.empty())
        throw ApiError(ErrorCode::InvalidArgument, "the occluder at this pixel has no name to follow; name it in the scene",
                       {{"/anchor", "the occluder has no name"}});
    if (q.anchor != protocol::StylizerPickRequest::Anchor::None)
        pick.anchor = core::anchorAtPixel(scene, q.x, q.y, pick.distance,
                                          q.anchor == protocol::StylizerPickRequest::Anchor::Object ? pick.occluder : -1);
    return pick;
}

namespace {

/// The diffusion layer of `tf` a constraint goes into (issue #36: core values, no JSON between):
/// `asked` when it names one, else the topmost diffusion layer, else a new one on top. A TF without
/// layers becomes one: its image (when it shows one) the first layer. Throws InvalidArgument when
/// `asked` is not a diffusion layer.
int diffusionLayerFor(core::TransferFunction& tf, std::optional<int> asked, int key) {
    if (tf.layers.empty() && tf.image) {
        core::TfLayer image;
        image.kind = core::TfLayerKind::Image;
        image.image = tf.image;
        tf.layers.push_back(std::move(image));
    }
    if (asked) {
        if (*asked < 0 || *asked >= int(tf.layers.size()) || tf.layers[size_t(*asked)].kind != core::TfLayerKind::Diffusion)
            throw ApiError(ErrorCode::InvalidArgument, "layer " + std::to_string(*asked) + " is not a diffusion layer of the TF" +
                                                           (key >= 0 ? " of key frame " + std::to_string(key) : std::string()),
                           {{"/layer", "must name a diffusion layer (GET …/stylizer lists them)"}});
        return *asked;
    }
    for (int i = int(tf.layers.size()); i-- > 0;)
        if (tf.layers[size_t(i)].kind == core::TfLayerKind::Diffusion) return i;
    core::TfLayer diffusion;
    diffusion.kind = core::TfLayerKind::Diffusion;
    tf.layers.push_back(std::move(diffusion));
    return int(tf.layers.size()) - 1;
}

}  // namespace

AddedTfConstraint SessionService::addTfConstraint(Session& s, const protocol::StylizerPickRequest& q) {
    const StylizerSnapshot seen = stylizer(s);
    AddedTfConstraint out;
    out.pick = pickIn(seen.scene, q);
    out.constraint = {out.pick.vBar, out.pick.depth, q.colour, q.alpha};
    if (q.anchor != protocol::StylizerPickRequest::Anchor::None) out.constraint.anchor = out.pick.anchor;
    out.key = out.pick.key;
    // The pick ran on the GL thread without the lock; the change is made under it, to the scene the
    // pick saw or not at all (a PUT in between would otherwise be lost, or the click land in a
    // scene it was not made in).
    std::lock_guard lock(s.mutex);
    if (s.stylizer.revision != seen.revision)
        throw ApiError(ErrorCode::Busy, "the stylizer's scene changed (revision " + std::to_string(seen.revision) + " → " +
                                            std::to_string(s.stylizer.revision) + ") while the pixel was picked; pick again");
    core::StylizerScene scene = s.stylizer.scene;
    auto& slot = out.key >= 0 ? scene.keyframes[size_t(out.key)].transferFunction : scene.transferFunction;
    core::TransferFunction& tf = slot ? *slot : slot.emplace();
    out.layer = diffusionLayerFor(tf, q.layer, out.key);
    auto& constraints = tf.layers[size_t(out.layer)].constraints;
    constraints.push_back(out.constraint);
    out.index = int(constraints.size()) - 1;
    try {
        scene.checkTfCompileWork();
        core::compileTransferFunction(tf);
    } catch (const InvalidArgument& e) {
        throw ApiError(ErrorCode::InvalidArgument, e.what(), {{"/transfer_function/layers", e.what()}});
    }
    out.revision = commitStylizerScene(s, std::move(scene), s.stylizer.meshRefs).revision;
    return out;
}

std::optional<LiveFrame> SessionService::nextLiveFrame(Session& s, uint64_t after, std::chrono::milliseconds wait) {
    StylizerSnapshot snapshot;
    {
        std::unique_lock lock(s.mutex);
        if (!s.stylizerChanged.wait_for(lock, wait, [&] { return s.removed || s.stylizer.revision > after; })) return std::nullopt;
        if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
        if (s.stylizer.live.revision == s.stylizer.revision) return s.stylizer.live;  // another stream rendered it
        snapshot = snapshotOf(s);
    }
    core::StylizeSettings settings;
    core::readBackOnly(settings, core::StylizerOutput::Frame);  // the stream sends the frame alone
    const auto t0 = Clock::now();
    const core::StylizedFrame f = stylizeOnGl(core::sceneAtTime(snapshot.scene, snapshot.scene.time), settings);
    LiveFrame live{snapshot.revision, core::encodeImage(f.frame, "jpeg"), f.frame.width, f.frame.height,
                   std::chrono::duration<double, std::milli>(Clock::now() - t0).count()};
    std::lock_guard lock(s.mutex);
    if (live.revision > s.stylizer.live.revision) s.stylizer.live = live;
    return live;
}

std::optional<LiveFrame> SessionService::liveFrame(Session& s, uint64_t revision) const {
    std::lock_guard lock(s.mutex);
    if (s.stylizer.live.revision != revision || revision == 0) return std::nullopt;
    return s.stylizer.live;
}

}  // namespace volstyle::server

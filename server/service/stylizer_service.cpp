// The stylizer of a session (SPEC §7 "API"): its scene, occluder meshes and transfer function,
// frames on the GL thread, and the live stream's frames.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/image/jpeg_encoder.h"
#include "core/stylize/mesh_io.h"
#include "core/stylize/keyframes.h"
#include "core/stylize/stylizer.h"
#include "core/stylize/tf_anchors.h"
#include "server/runtime/mesh_reader.h"
#include "server/service/services.h"

namespace volstyle::server {
namespace {

using Clock = std::chrono::steady_clock;


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

/// The stylizer's state as a render reads it: the scene, its mesh references and revision. The session's lock held.
StylizerSnapshot snapshotOf(Session& s) {
    return {s.stylizer.scene, s.stylizer.meshRefs, s.stylizer.revision};
}

}  // namespace

StylizerSnapshot StylizerService::stylizer(Session& s) const {
    std::lock_guard lock(s.mutex);
    return snapshotOf(s);
}

void StylizerService::checkStylizerCameras(const core::StylizerScene& scene) const {
    auto checkSize = [&](const core::Camera& camera, const std::string& path) {
        for (auto [side, name] : {std::pair{camera.width, "width"}, std::pair{camera.height, "height"}})
            if (side > m_ctx.limits.maxImageSide) {
                const std::string message = "images are limited to " + std::to_string(m_ctx.limits.maxImageSide) + " pixels a side";
                throw ApiError(ErrorCode::TooLarge, message, {{path + "/" + name, message}});
            }
    };
    checkSize(scene.camera, "/camera");
    for (size_t k = 0; k < scene.keyframes.size(); ++k) checkSize(scene.keyframes[k].camera, "/keyframes/" + std::to_string(k) + "/camera");
}

StylizerSnapshot StylizerService::commitStylizerScene(Session& s, core::StylizerScene scene, std::vector<std::string> meshRefs) {
    try {
        scene.validate();
    } catch (const InvalidArgument& e) {
        throw ApiError(ErrorCode::InvalidArgument, e.what());
    }
    // A change of time alone (scrubbing, playing) or none at all is not a step to undo.
    const bool step = !sameSceneApartFromTime(s.stylizer.scene, scene) || meshRefs != s.stylizer.meshRefs;
    if (step) {
        remember(s.stylizer.undo, currentSceneEntry(s.stylizer));
        s.stylizer.redo.clear();
    }
    s.stylizer.scene = std::move(scene);
    s.stylizer.meshRefs = std::move(meshRefs);
    m_ctx.stylizerChanged(s, step);
    return snapshotOf(s);
}

StylizerSnapshot StylizerService::setStylizerScene(Session& s, const protocol::StylizerSceneRequest& request) {
    checkStylizerCameras(request.scene);
    std::lock_guard lock(s.mutex);
    return commitStylizerScene(s, resolveStylizerScene(s.stylizer, request, &s.volume.current), request.meshRefs);
}

StylizerSnapshot StylizerService::undoStylizer(Session& s, bool redo) {
    std::lock_guard lock(s.mutex);
    auto& from = redo ? s.stylizer.redo : s.stylizer.undo;
    auto& to = redo ? s.stylizer.undo : s.stylizer.redo;
    if (from.empty()) throw ApiError(ErrorCode::Busy, redo ? "nothing to redo" : "nothing to undo");
    core::StylizerScene scene;
    try {
        scene = resolveSceneEntry(s.stylizer, from.back());
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
    m_ctx.stylizerChanged(s, true);
    return snapshotOf(s);
}


void StylizerService::checkRenderBudget(const core::StylizerScene& scene, const core::StylizeSettings& settings) {
    // Other sessions' frames and a solve's next iteration wait behind this one: estimate it first.
    const double seconds = stylizerSeconds(scene, settings);
    if (m_ctx.limits.renderBudgetSeconds > 0 && seconds > m_ctx.limits.renderBudgetSeconds)
        throw ApiError(ErrorCode::OverBudget,
                       fmt::format("this frame would take about {:.0f} s, over the render budget of {:g} s (volstyle serve --render-budget); "
                                   "use fewer pixels, {}a smaller shadow map or shorter dilations",
                                   seconds, m_ctx.limits.renderBudgetSeconds,
                                   settings.method == core::VisibilityMethod::Naive ? "fewer steps or the accelerated method, " : ""));
}

core::StylizedFrame StylizerService::stylizeOnGl(Session& s, const core::StylizerScene& scene, const core::StylizeSettings& settings) {
    checkRenderBudget(scene, settings);
    return m_ctx.gl->run([&](core::GpuDevice& device) {
        // A heterogeneous medium is the session's volume as the renderer holds it (no copy).
        const std::shared_ptr<core::GpuVolume> medium = scene.volume ? m_ctx.lockedSessionGpu(s) : nullptr;
        return m_ctx.stylizerEngine(device).render(scene, settings, medium.get());
    });
}

core::StylizedFrame StylizerService::stylize(Session& s, const protocol::StylizerFrameRequest& request) {
    core::StylizerScene scene = sceneFor(stylizer(s).scene, request.camera, request.time);
    core::StylizeSettings settings = request.settings;
    core::readBackOnly(settings, request.output);
    return stylizeOnGl(s, scene, settings);
}

StylizerPick StylizerService::pickStylizer(Session& s, const protocol::StylizerPickRequest& q) { return pickIn(s, stylizer(s).scene, q); }

StylizerPick StylizerService::pickIn(Session& s, const core::StylizerScene& sessionScene, const protocol::StylizerPickRequest& q) {
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
    const core::StylizedFrame f = stylizeOnGl(s, scene, settings);
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

AddedTfConstraint StylizerService::addTfConstraint(Session& s, const protocol::StylizerPickRequest& q) {
    const StylizerSnapshot seen = stylizer(s);
    AddedTfConstraint out;
    out.pick = pickIn(s, seen.scene, q);
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

std::unique_ptr<LiveStreamPipeline> StylizerService::liveStreamPipeline(std::shared_ptr<Session> s) const {
    return std::make_unique<LiveStreamPipeline>(*m_ctx.gl, std::move(s));
}

std::future<RenderedLiveFrame> StylizerService::startLiveFrame(LiveStreamPipeline& pipeline, const StylizerSnapshot& snapshot) {
    core::StylizeSettings settings;
    core::readBackOnly(settings, core::StylizerOutput::Frame);  // the stream sends the frame alone
    core::StylizerScene scene = core::sceneAtTime(snapshot.scene, snapshot.scene.time);
    checkRenderBudget(scene, settings);
    return m_ctx.gl->start([this, &pipeline, session = pipeline.sessionPtr(), scene = std::move(scene), settings,
                            revision = snapshot.revision](core::GpuDevice& device) {
        const auto t0 = Clock::now();
        const std::shared_ptr<core::GpuVolume> medium = scene.volume ? m_ctx.lockedSessionGpu(*session) : nullptr;
        const core::DisplayReadback display{&pipeline.ring(), 0.0};
        RenderedLiveFrame r{revision, m_ctx.stylizerEngine(device).render(scene, settings, medium.get(), &display), scene.camera.width,
                            scene.camera.height, 0};
        r.renderMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        return r;
    });
}

std::optional<LiveFrame> StylizerService::nextLiveFrame(LiveStreamPipeline& pipeline, uint64_t after, std::chrono::milliseconds wait) {
    Session& s = pipeline.session();
    RenderedLiveFrame r;
    if (pipeline.next.valid()) {
        try {
            r = pipeline.next.get();  // rendered while the last frame was encoded and sent
        } catch (...) {
            pipeline.failedRevision = pipeline.nextRevision;
            throw;
        }
    } else {
        StylizerSnapshot snapshot;
        {
            std::unique_lock lock(s.mutex);
            if (!s.changed.wait_for(lock, wait, [&] { return s.removed || s.stylizer.revision > after; })) return std::nullopt;
            if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
            if (s.stylizer.live.revision == s.stylizer.revision) return s.stylizer.live;  // another stream rendered it
            snapshot = snapshotOf(s);
        }
        try {
            r = startLiveFrame(pipeline, snapshot).get();
        } catch (...) {
            pipeline.failedRevision = snapshot.revision;
            throw;
        }
    }
    // The newest revision renders on the GL thread while this frame is encoded and sent (a
    // burst of changes renders only its last: a slow client gets the newest frame, no backlog).
    try {
        std::unique_lock lock(s.mutex);
        if (!s.removed && s.stylizer.revision > r.revision && s.stylizer.live.revision < s.stylizer.revision) {
            const StylizerSnapshot snapshot = snapshotOf(s);
            lock.unlock();
            pipeline.next = startLiveFrame(pipeline, snapshot);
            pipeline.nextRevision = snapshot.revision;
        }
    } catch (...) {  // e.g. over the budget: the next call renders it again and reports that
    }
    const auto e0 = Clock::now();
    LiveFrame live;
    try {
        live = {r.revision,
                r.frame.displayBytes ? core::encodeJpegRgbx(r.frame.displayBytes, r.width, r.height, kLiveJpegQuality)
                                     : core::encodeJpeg(r.frame.frame, kLiveJpegQuality),
                r.width, r.height, r.renderMs, 0};
    } catch (...) {
        pipeline.release(r);
        throw;
    }
    pipeline.release(r);
    live.encodeMs = std::chrono::duration<double, std::milli>(Clock::now() - e0).count();
    std::lock_guard lock(s.mutex);
    if (live.revision > s.stylizer.live.revision) s.stylizer.live = live;
    return live;
}

std::optional<LiveFrame> StylizerService::liveFrame(Session& s, uint64_t revision) const {
    std::lock_guard lock(s.mutex);
    if (s.stylizer.live.revision != revision || revision == 0) return std::nullopt;
    return s.stylizer.live;
}

double StylizerService::stylizerLookupsPerSecond() {
    std::call_once(m_stylizerSpeedOnce, [this] {
        double measured = 0;
        try {
            // Once, when the stylizer first starts on this device (not at every server start: a
            // server that never stylizes should not pay for it).
            measured = m_ctx.gl->run([this](core::GpuDevice& device) { return m_ctx.stylizerEngine(device).measureLookupsPerSecond(); });
        } catch (const std::exception& e) {
            spdlog::warn("the stylizer's speed could not be measured ({}); frames are estimated at {:g} lookups/s", e.what(),
                         kMinStylizerLookupsPerSecond);
        }
        m_stylizerLookupsPerSecond = std::max(measured, kMinStylizerLookupsPerSecond);
        spdlog::info("stylizer: {:.3g} lookups/s measured on this device; frame estimates use {:.3g}", measured, m_stylizerLookupsPerSecond);
    });
    return m_stylizerLookupsPerSecond;
}

double StylizerService::stylizerSeconds(const core::StylizerScene& scene, const core::StylizeSettings& settings) {
    return core::Stylizer::estimatedLookups(scene, settings) / stylizerLookupsPerSecond();
}

}  // namespace volstyle::server

#include "server/service/services.h"

#include "core/solve/solve_cache.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <ctime>
#include <filesystem>

#include "core/base/errors.h"
#include "core/image/clipped_pixels.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/translucent/translucent_renderer.h"
#include "core/stylize/stylizer.h"
#include "core/volume/builtin_scenes.h"
#include "server/runtime/gl_worker.h"
#include "server/runtime/mesh_reader.h"
#include "server/state/session_info.h"

namespace volstyle::server {
std::shared_ptr<Session> SessionsService::create(const protocol::CreateSessionRequest& request) {
    // Refuse before building the scene (a 256³ one takes seconds); add() re-checks under its lock.
    if (m_ctx.sessions.size() >= m_ctx.limits.maxSessions) throw tooManySessions(m_ctx.limits.maxSessions);
    auto s = std::make_shared<Session>();
    s->created = isoNow();
    s->scene = request.scene;
    m_ctx.memory.checkNew(size_t(request.resolution) * request.resolution * request.resolution * 9 * sizeof(float), "a new session");
    s->volume.current = core::makeBuiltinScene(request.builtinName(), request.resolution);  // InvalidArgument lists the scenes
    s->light.lighting = core::defaultLighting();
    s->volume.versions.add(1);
    m_ctx.sessions.add(s);
    std::lock_guard lock(s->mutex);
    m_ctx.saved(*s);
    return s;
}

void SessionsService::remove(const std::string& id) {
    if (m_ctx.persist && m_ctx.persist->hasMirror()) m_ctx.find(id);  // one only the store holds (another replica made it) is read first
    auto s = m_ctx.sessions.remove(id);
    if (!s) throw ApiError(ErrorCode::NotFound, "no session '" + id + "'");
    std::vector<std::string> jobs;
    {
        std::lock_guard lock(s->mutex);
        s->removed = true;  // from now on nothing writes it back or caches a GPU copy
        m_ctx.memory.forget(*s);
        jobs = s->jobs;
        if (m_ctx.persist) m_ctx.persist->removeSession(s->id);
    }
    s->changed.notify_all();  // its live streams end
    bool holdsGpu = false;
    {
        std::lock_guard lock(s->mutex);
        holdsGpu = s->volume.gpu != nullptr;
    }
    for (const auto& jid : jobs)
        if (auto j = m_ctx.jobs.find(jid)) {
            j->cancel = true;
            std::lock_guard lock(j->mutex);
            holdsGpu |= j->preview != nullptr;
        }
    if (!holdsGpu) return;  // nothing for the GL thread to free
    m_ctx.gl->run([this, s](core::GpuDevice&) {
        std::lock_guard lock(s->mutex);
        s->volume.gpu.reset();
        m_ctx.dropPreviews(*s);
    });
}

SessionsService::Listed SessionsService::summaryOfUnsummed(const std::string& id) const {
    // A record an older volstyle saved: held here, its state; else its summary is written to the
    // store once (read from the store's files, not kept), and every replica lists it from then on.
    if (auto held = m_ctx.sessions.find(id)) return {id, sessionInfo(*held), ""};
    try {
        std::lock_guard lock(m_ctx.storeLoads);  // as freshFromStore: one load of a session at a time
        if (auto held = m_ctx.sessions.find(id)) return {id, sessionInfo(*held), ""};  // loaded meanwhile: its folder is in use
        if (auto text = m_ctx.persist->summarizeStored(id)) return {id, std::nullopt, std::move(*text)};
    } catch (const std::exception& e) {
        spdlog::warn("session {}: not listed, its record could not be read: {}", id, e.what());
    }
    return {};  // gone, or unreadable: not listed
}

std::vector<SessionsService::Listed> SessionsService::list() const {
    std::vector<Listed> out;
    const bool stored = m_ctx.persist && m_ctx.persist->hasMirror();
    if (stored) {
        Persistence::StoredSessions all = m_ctx.persist->storedSessions();
        for (auto& [id, text] : all.summaries) out.push_back({id, std::nullopt, std::move(text)});
        for (const auto& id : all.unsummed) out.push_back(summaryOfUnsummed(id));
        std::erase_if(out, [](const Listed& l) { return l.id.empty(); });
    }
    // A stored session held here is listed above if it still exists (another replica may have
    // deleted it); only the ones that never go to the store come from memory.
    for (auto& s : m_ctx.sessions.all())
        if (!stored || !SessionStore::isStoreId(s->id)) out.push_back({s->id, sessionInfo(*s), ""});
    return out;
}

core::Lighting SessionsService::setLighting(Session& s, const protocol::LightingRequest& request) {
    std::lock_guard lock(s.mutex);
    s.light.lighting = request.resolve(s.light.environmentMap);
    m_ctx.saved(s);
    m_ctx.shownChanged(s);
    return s.light.lighting;
}

std::shared_ptr<const core::Image> SessionsService::environmentMapIfAny(Session& s) const {
    std::lock_guard lock(s.mutex);
    return s.light.environmentMap;
}

SessionView SessionsService::addView(Session& s, const core::Camera& camera, std::optional<int> frame) {
    std::lock_guard lock(s.mutex);
    s.views.list.push_back({"v" + std::to_string(s.views.next++), camera, std::nullopt, std::nullopt, nullptr, frame});
    m_ctx.saved(s);
    return s.views.list.back();
}

void SessionsService::removeView(Session& s, const std::string& viewId) {
    std::lock_guard lock(s.mutex);
    findView(s, viewId);  // 404 if absent
    std::erase_if(s.views.list, [&](const SessionView& v) { return v.id == viewId; });
    if (m_ctx.persist) m_ctx.persist->removeView(s.id, viewId);
    m_ctx.saved(s);
}

const char* viewImageName(ViewImage kind) {
    switch (kind) {
        case ViewImage::Target: return "target";
        case ViewImage::Weights: return "weights";
        default: return "background";
    }
}

SessionView SessionsService::setViewImage(Session& s, const std::string& viewId, ViewImage kind, const std::string& bytes, bool clipAware) {
    const bool isTarget = kind == ViewImage::Target;
    const std::string what = isTarget ? "the target" : kind == ViewImage::Weights ? "the weight image" : "the background plate";
    m_ctx.checkUploadSize(bytes, what);
    const core::Camera camera = m_ctx.view(s, viewId).camera;  // 404 before any decode
    // The size is checked from the header, before any pixel is decoded, and at most
    // kConcurrentDecodes uploads decode at once: six parallel 4096² PNGs to a 64² view once took
    // 5.8 GiB to refuse.
    std::optional<ServiceContext::DecodeSlot> slot;
    const auto checkHeader = [&](int width, int height) {
        if (width != camera.width || height != camera.height)
            throw ApiError(ErrorCode::InvalidArgument, "the image is " + std::to_string(width) + "x" + std::to_string(height) +
                                                           " but view " + viewId + " renders " + std::to_string(camera.width) +
                                                           "x" + std::to_string(camera.height));
        slot.emplace(m_ctx.decodeSlots);
    };
    core::Image image;
    size_t clipped = 0;
    try {
        const core::LoadedImage loaded = core::loadImageFromMemory(bytes.data(), bytes.size(), what, m_ctx.limits.maxImageSide, checkHeader);
        image = isTarget ? core::pictureOf(loaded) : loaded.image;  // a render EXR as a target: the picture it shows
        // Painted over an 8/16-bit picture: where it was clipped, the paint says nothing (issue #37).
        if (isTarget && clipAware && loaded.wasSrgb) clipped = core::ignoreClippedPixels(image);
    } catch (const Error& e) {
        throw ApiError(ErrorCode::UnsupportedMedia, e.what());  // undecodable, or over the side limit
    }
    // Weights are the target's alpha (or the weight image's first channel), a plate is radiance:
    // negative values would be solved on silently; refuse them here, where the client can fix the
    // file. (The decoder already refuses NaN and Inf.)
    const int channels = isTarget ? 4 : kind == ViewImage::Weights ? 1 : 3;
    size_t negative = 0;
    for (size_t i = 0; i < image.pixelCount(); ++i)
        for (int c = 0; c < channels; ++c) negative += image.rgba[4 * i + size_t(c)] < 0 ? 1 : 0;
    if (negative)
        throw ApiError(ErrorCode::InvalidArgument, what + " has " + std::to_string(negative) +
                                                       " negative values; colours and weights must be >= 0");
    if (kind == ViewImage::Background)  // a plate is opaque: its alpha means nothing
        for (size_t i = 0; i < image.pixelCount(); ++i) image.rgba[4 * i + 3] = 1;
    slot.reset();
    std::lock_guard lock(s.mutex);
    SessionView& v = findView(s, viewId);  // views keep their camera: the header check still holds
    const std::optional<core::Image>& held = kind == ViewImage::Target ? v.target : v.weights;
    const size_t replaced = kind == ViewImage::Background ? (v.background ? v.background->rgba.size() : 0) : (held ? held->rgba.size() : 0);
    m_ctx.memory.check(s, image.rgba.size() * sizeof(float), replaced * sizeof(float), "the " + std::string(viewImageName(kind)) + " of " + v.id);
    if (m_ctx.persist) m_ctx.persist->saveViewImage(s.id, v.id, viewImageName(kind), image);
    switch (kind) {
        case ViewImage::Target: v.target = std::move(image), v.clippedPixels = clipped; break;
        case ViewImage::Weights: v.weights = std::move(image); break;
        case ViewImage::Background: v.background = std::make_shared<const core::Image>(std::move(image)); break;
    }
    m_ctx.saved(s);
    return v;
}

SessionView SessionsService::removeViewImage(Session& s, const std::string& viewId, ViewImage kind) {
    std::lock_guard lock(s.mutex);
    SessionView& v = findView(s, viewId);
    const bool had = kind == ViewImage::Target ? v.target.has_value() : kind == ViewImage::Weights ? v.weights.has_value() : bool(v.background);
    if (!had) throw ApiError(ErrorCode::NotFound, "view " + v.id + " has no " + viewImageName(kind));
    if (m_ctx.persist) m_ctx.persist->removeViewImage(s.id, v.id, viewImageName(kind));
    if (kind == ViewImage::Target) v.target.reset();
    else if (kind == ViewImage::Weights) v.weights.reset();
    else v.background.reset();
    m_ctx.saved(s);
    return v;
}

SessionsService::Readiness SessionsService::readiness() const {
    Readiness r;
    r.store = m_ctx.persist ? m_ctx.persist->describe() : "memory";
    if (m_ctx.persist) r.storeProblem = m_ctx.persist->writeProblem();
    if (m_ctx.gl->queueDepth().stopping) r.glProblem = "the GL thread is stopping";
    else if (m_ctx.gl->capabilities().renderer.empty()) r.glProblem = "no GL context";
    return r;
}

std::vector<QuarantineEntry> SessionsService::quarantine() const {
    return m_ctx.persist ? m_ctx.persist->quarantine() : std::vector<QuarantineEntry>{};
}

}  // namespace volstyle::server

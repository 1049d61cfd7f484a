// The painting page's viewport stream (viewport_service.h): its state and each frame's render.
#include "server/service/viewport_service.h"

#include "core/image/jpeg_encoder.h"

namespace volstyle::server {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

void throwIfRemoved(const Session& s) {
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
}

}  // namespace

ViewportKey ViewportService::set(Session& s, protocol::RenderRequest request) {
    std::lock_guard lock(s.mutex);
    throwIfRemoved(s);
    s.viewport.request = std::move(request);
    ++s.viewport.revision;
    s.changed.notify_all();
    return {s.viewport.revision, s.shownRevision};
}

ViewportKey ViewportService::current(Session& s) const {
    std::lock_guard lock(s.mutex);
    throwIfRemoved(s);
    return {s.viewport.revision, s.shownRevision};
}

std::optional<ViewportFrame> ViewportService::next(Session& s, const ViewportKey& after, std::chrono::milliseconds wait,
                                                   ViewportKey* attempted) {
    ViewportFrame f;
    protocol::RenderRequest request;
    {
        std::unique_lock lock(s.mutex);
        const auto due = [&] { return s.removed || (s.viewport.revision > 0 && !(ViewportKey{s.viewport.revision, s.shownRevision} == after)); };
        if (!s.changed.wait_for(lock, wait, due)) return std::nullopt;
        throwIfRemoved(s);
        f.key = {s.viewport.revision, s.shownRevision};
        f.version = s.volume.version;
        request = s.viewport.request;
    }
    if (attempted) *attempted = f.key;
    const auto t0 = Clock::now();
    const core::Image picture = request.mode == protocol::RenderMode::Translucent
                                    ? m_volumes.renderTranslucent(s, request.camera, request.translucent)
                                    : m_volumes.render(s, request.camera).beauty;
    f.renderMs = msSince(t0);
    const auto e0 = Clock::now();
    f.jpeg = core::encodeJpeg(picture, kLiveJpegQuality, request.exposure);
    f.encodeMs = msSince(e0);
    f.width = picture.width;
    f.height = picture.height;
    return f;
}

}  // namespace volstyle::server

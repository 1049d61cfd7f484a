#pragma once
/// \file viewport_service.h
/// The painting page's viewport as a live stream (issue #40 item 4): the page PUTs its camera and
/// render options (a RenderRequest) and reads one long-lived response of JPEG frames. A frame is
/// rendered when the viewport moves or what the session shows changes (a new version, the
/// lighting, the environment map); a burst of moves renders only the newest, so a slow link gets
/// the newest frame next, never a backlog.

#include <chrono>
#include <cstdint>
#include <optional>

#include "server/service/volume_service.h"

namespace volstyle::server {

/// Where a viewport stream stands: the viewport's revision and the session's shownRevision that
/// its last frame rendered. A frame is due when either moved.
struct ViewportKey {
    uint64_t revision = 0, shown = 0;
    bool operator==(const ViewportKey&) const = default;
};

struct ViewportFrame {
    ViewportKey key;
    int version = 0;    ///< the session's version when the render began
    std::string jpeg;
    int width = 0, height = 0;
    double renderMs = 0, encodeMs = 0;
};

class ViewportService {
public:
    ViewportService(ServiceContext& ctx, VolumeService& volumes) : m_ctx(ctx), m_volumes(volumes) {}

    /// Sets the viewport (its format is ignored: the stream sends JPEG); its new revision and
    /// what the session shows now (the key of the first frame that shows it).
    ViewportKey set(Session& s, protocol::RenderRequest request);
    /// The viewport's revision and what the session shows now (GET …/viewport).
    ViewportKey current(Session& s) const;
    /// Waits up to `wait` for a frame newer than `after` to be due, then renders and encodes it
    /// (nullopt: nothing changed). not_found once the session is deleted; a render's own error
    /// (e.g. over the render budget) is thrown, and the next call waits for the next change.
    /// `attempted` gets the key of the frame it renders before it renders it: after a failure,
    /// the key to wait past (a move made meanwhile still renders).
    std::optional<ViewportFrame> next(Session& s, const ViewportKey& after, std::chrono::milliseconds wait, ViewportKey* attempted = nullptr);

private:
    ServiceContext& m_ctx;
    VolumeService& m_volumes;
};

}  // namespace volstyle::server

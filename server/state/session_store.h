#pragma once
/// \file session_store.h
/// Editing sessions held by the server: the volume (and its GPU copy, owned by the GL thread),
/// the lighting, and bookkeeping. Ids are 128 random bits in hex (unguessable, SPEC §3).

#include <condition_variable>
#include <map>
#include <optional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/render/gpu_volume.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_options.h"
#include "core/volume/volume.h"
#include "protocol/error_code.h"
#include "protocol/requests.h"
#include "protocol/response_values.h"
#include "server/state/stylizer_state.h"
#include "server/state/version_history.h"

namespace volstyle::server {

/// A file of a session found unreadable and moved to the quarantine (persistence.h).
struct DamagedFile {
    std::string file;    ///< relative to the session's directory, e.g. "versions/3.vdb"
    std::string reason;
};

/// A view of a session: a camera, and the painted target (alpha = weight), weights and background
/// plate once uploaded.
struct SessionView {
    std::string id;  ///< "v1", "v2", …
    core::Camera camera;
    std::optional<core::Image> target;
    std::optional<core::Image> weights;
    /// The background plate (SPEC §1): what this view sees behind the volume, replacing the
    /// lighting's background in its renders and solves. Shared: renders hold it, never copy it.
    std::shared_ptr<const core::Image> background = nullptr;
    /// The frame of the session's animation this view shows (issue #16), or none: the session's
    /// volume. Views of frames are solved by POST …/animate, not POST …/solve.
    std::optional<int> frame = std::nullopt;
    /// Target pixels given weight 0 on upload because the image was clipped there (clip-aware).
    size_t clippedPixels = 0;
};

/// A frame of the session's animation (issue #16): its volume as uploaded, or as the last
/// POST …/animate left it (`solved`).
struct SessionFrame {
    core::Volume volume;
    bool solved = false;
};

/// A session's volume (issue #36: the session split by concern): the current one, its number,
/// every committed version, and its GPU copy.
struct VolumeState {
    core::Volume current;
    int version = 1;
    VersionHistory versions;                    ///< every committed version, for revert and download
    std::shared_ptr<core::GpuVolume> gpu;       ///< created and destroyed on the GL thread
    /// The version whose content the current one is: its own number after an edit, the version
    /// an undo, redo or revert brought back otherwise (every step is a new version: nothing lost).
    int shows = 1;
    /// POST …/undo and …/redo: what each step brings back, newest last. An edit (solve, upload,
    /// perturbation, refraction, revert) pushes what was shown onto `undo` and clears `redo`.
    std::vector<int> undo, redo;
};

/// A session's views, and the next view's number ("v1", "v2", … never reused).
struct ViewsState {
    std::vector<SessionView> list;
    int next = 1;
};

/// A session's lighting, and the uploaded lat-long map (PUT …/environment) that the lighting
/// names "session" (its background.environment and environment.map point at it).
struct LightingState {
    core::Lighting lighting;
    std::shared_ptr<const core::Image> environmentMap;
};

/// The painting page's viewport (PUT …/viewport, issue #40): the render its live stream shows.
struct ViewportState {
    protocol::RenderRequest request;
    uint64_t revision = 0;  ///< moves with each PUT; 0: never set (the stream waits for one)
};

struct Session {
    std::string id;
    std::string created;  ///< ISO 8601, UTC
    std::string scene;    ///< where the volume came from
    VolumeState volume;
    ViewsState views;
    LightingState light;
    std::map<int, SessionFrame> frames;    ///< the animation's frames by number (docs/ANIMATION.md)
    StylizerState stylizer = defaultStylizer();
    std::vector<std::string> jobs;
    std::vector<DamagedFile> damaged;      ///< files of the session found unreadable (quarantined)
    ViewportState viewport;
    /// The options of its last solve (in memory only): what the server prepares the next one for
    /// while the artist paints (server/service/solve_prefetch.cpp).
    std::optional<core::SolveOptions> lastSolveOptions;
    /// Moves (with `mutex`) when what a render of the session shows changes: a new version, the
    /// lighting, the environment map. The viewport's stream renders again when it moves.
    uint64_t shownRevision = 0;
    /// Notified (with `mutex`) when the stylizer's revision, the viewport or shownRevision moves,
    /// and when the session is deleted: what live streams wait on.
    std::condition_variable changed;
    /// Set by DELETE: work still queued for the session neither caches GPU copies nor writes it
    /// back to disk (it answers not_found instead).
    bool removed = false;
    /// What the server's MemoryBudget charges it (memory_budget.h; kept with the budget's lock).
    size_t chargedBytes = 0;
    /// With a PostgreSQL store: the stamp of its record there as this server last wrote or read
    /// it. Another replica's write changes the stamp, and the next request reloads the session.
    uint64_t storeStamp = 0;
    std::mutex mutex;                      ///< guards the fields above
};

using protocol::EnvironmentMapInfo;
/// The session's environment map, if any (call with its lock held).
std::optional<EnvironmentMapInfo> environmentMapInfo(const Session& s);

/// The view `id` of `s` (its lock held); ApiError not_found names both.
SessionView& findView(Session& s, const std::string& id);

/// Now, as ISO 8601 UTC ("2026-12-02T03:37:32Z").
std::string isoNow();

/// The answer when the server holds `max` sessions already.
protocol::ApiError tooManySessions(size_t max);

class SessionStore {
public:
    explicit SessionStore(size_t maxSessions) : m_max(maxSessions) {}
    /// Adds a session with a fresh id; throws ApiError too_many_sessions when full (checked under
    /// the store's lock, so concurrent creates cannot pass the limit).
    std::shared_ptr<Session> add(std::shared_ptr<Session> s);
    void restore(std::shared_ptr<Session> s);  ///< keeps its id (restart)
    std::shared_ptr<Session> find(const std::string& id) const;  ///< nullptr if unknown
    std::shared_ptr<Session> remove(const std::string& id);      ///< nullptr if unknown
    std::vector<std::shared_ptr<Session>> all() const;
    size_t size() const;

    static std::string newId();
    /// Whether `id` could be a session's or job's id (hex digits, at most 64): anything else is
    /// not asked of the store.
    static bool isStoreId(const std::string& id) {
        return !id.empty() && id.size() <= 64 && id.find_first_not_of("0123456789abcdef") == std::string::npos;
    }

private:
    size_t m_max;
    mutable std::mutex m_mutex;
    std::map<std::string, std::shared_ptr<Session>> m_sessions;
};

}  // namespace volstyle::server

#pragma once
/// \file session_service.h
/// What the API does to sessions, views, volume versions and solve jobs, without HTTP: route
/// handlers parse a protocol request and call one method here. Every change is on disk
/// (Persistence) before the method returns; GL work runs on the GL thread (a GlExecutor: the server's GlWorker, or a test's fake); a session's
/// lock is never held while waiting for the GL thread (a finishing solve needs it).

#include <chrono>
#include <mutex>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <semaphore>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/render/renderer.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_options.h"
#include "core/volume/volume.h"
#include "protocol/render_json.h"
#include "protocol/requests.h"
#include "server/runtime/gl_executor.h"
#include "server/state/job_store.h"
#include "server/service/memory_budget.h"
#include "server/store/persistence.h"
#include "server/state/session_store.h"
#include "server/runtime/vdb_reader.h"
#include "server/state/stylizer_state.h"

namespace volstyle::core {
class Stylizer;
class SolveCache;
class TranslucentRenderer;
struct TranslucentSettings;
struct StylizedFrame;
}  // namespace volstyle::core

namespace volstyle::server {

struct ServiceLimits {
    size_t maxSessions = 64;
    size_t maxQueuedJobs = 4;  ///< per session
    size_t maxUploadBytes = size_t(512) << 20;
    int maxImageSide = 4096;
    core::VolumeLimits volumeLimits;
    /// Occluder meshes: each file (also within maxUploadBytes) and its vertices and triangles;
    /// maxVertices also bounds the vertices of all a session's uploads together.
    core::MeshLimits meshLimits;
    size_t maxMeshesPerSession = 16;
    /// Seconds a render or preview may hold the GL thread (over: 422 over_budget); <= 0: unbounded.
    double renderBudgetSeconds = 60;
    VdbReaderOptions vdbReader;  ///< uploads are read in a child process first (vdb_reader.h)
    /// Finished jobs kept (memory and disk; GET /jobs/{id} of an older one: 404). Unfinished
    /// jobs are always kept.
    size_t finishedJobsKept = 256;
    /// GPU memory for the parts one solve leaves for the next (core/solve/solve_cache.h), shared by
    /// every session: the keys name content, not sessions. 0: every solve starts cold.
    size_t solveCacheBytes = size_t(1) << 30;
    /// Decoded bytes a session, and all sessions, may hold (memory_budget.h; over: 507).
    MemoryLimits memory;
};

enum class ViewImage { Target, Weights, Background };
/// "target", "weights", "background": its name in routes, files and "has_…" fields.
const char* viewImageName(ViewImage kind);

/// What a session's stylizer renders (a copy: the meshes are shared, not copied).
struct StylizerSnapshot {
    core::StylizerScene scene;
    std::vector<std::string> meshRefs;
    uint64_t revision = 0;
};

/// What a click at a pixel of the stylizer's frame finds (POST …/stylizer/pick): the pixel's TF
/// position (V̄ and linear depth d), its distance, the occluder seen there and the point.
struct StylizerPick {
    int x = 0, y = 0;
    double vBar = 0, depth = 0, distance = 0;
    int occluder = -1;         ///< index in the scene; −1: the sky (no surface)
    std::string occluderName;  ///< empty for the sky
    Vec3d position;            ///< the world point at `distance` along the pixel's ray
    core::TfAnchor anchor;     ///< what the request's `anchor` asked for (position empty for "none")
    /// The TF a constraint there goes into: on a path whose keys carry TFs, the key nearest the
    /// time (its depth range gives `depth`); −1: the scene's own.
    int key = -1;
};

/// A constraint clicked into the scene (POST …/stylizer/constraints).
struct AddedTfConstraint {
    StylizerPick pick;
    int layer = 0, index = 0;  ///< where it went: transfer_function/layers/{layer}/constraints/{index}
    int key = -1;              ///< … of key frame `key` (on a path whose keys carry TFs); −1: the scene's TF
    core::TfConstraint constraint;
    uint64_t revision = 0;
};

struct OccluderMeshInfo {
    std::string name, format;
    size_t vertices = 0, triangles = 0, fileBytes = 0;
    Vec3 boundsLo, boundsHi;  ///< in the mesh's own space
    bool used = false;              ///< the scene's occluders use it
};

struct TransferImageInfo {
    int width = 0, height = 0, channels = 0;
    bool used = false;  ///< the scene has a transfer_function
};

class SessionService {
public:
    /// Restores sessions and jobs from `dataDir` (empty: in memory only). GL work goes to `gl`;
    /// none given: the service starts its own GL thread (GlWorker).
    SessionService(ServiceLimits limits, const std::string& dataDir, std::unique_ptr<GlExecutor> gl = nullptr);
    ~SessionService();  ///< frees GPU copies on the GL thread, then stops it

    const core::gl::Capabilities& capabilities() const { return m_gl->capabilities(); }

    // Sessions.
    std::shared_ptr<Session> create(const protocol::CreateSessionRequest& request);
    std::shared_ptr<Session> find(const std::string& id) const;  ///< ApiError not_found
    std::vector<std::shared_ptr<Session>> all() const { return m_sessions.all(); }
    void remove(const std::string& id);
    core::Lighting lighting(Session& s) const;
    /// Sets the lighting, "session" resolved to the session's map (ValidationError naming the
    /// field without one); the lighting as set.
    core::Lighting setLighting(Session& s, const protocol::LightingRequest& request);
    /// The lighting (and the solve result's) as JSON, naming the session's map "session".
    nlohmann::json lightingJson(Session& s, const core::Lighting& lighting) const;

    // The session's environment map (session_environment.cpp; docs/LIGHTING.md).
    /// Decodes and stores a lat-long map (2:1, finite, >= 0; 422 otherwise, 413 over the limits);
    /// a lighting that names it now uses this one.
    EnvironmentMapInfo setEnvironmentMap(Session& s, const std::string& bytes);
    std::shared_ptr<const core::Image> environmentMap(Session& s) const;  ///< not_found without one
    void removeEnvironmentMap(Session& s);  ///< busy (409) while the lighting names it


    // Views.
    SessionView addView(Session& s, const core::Camera& camera, std::optional<int> frame = std::nullopt);
    SessionView view(Session& s, const std::string& viewId) const;  ///< a copy; ApiError not_found
    void removeView(Session& s, const std::string& viewId);
    /// Decodes an uploaded image (413 over the upload limit, 422 undecodable or over the side
    /// limit) and stores it as the view's target or weights.
    SessionView setViewImage(Session& s, const std::string& viewId, ViewImage kind, const std::string& bytes);
    /// Forgets the view's image of `kind` (not_found without one).
    SessionView removeViewImage(Session& s, const std::string& viewId, ViewImage kind);

    // Volume versions.
    int revert(Session& s, int version);                          ///< the new version number
    /// Bakes the perturbation (core/translucent/perturbation.h) into a new version; its number.
    int perturb(Session& s, const core::Perturbation& perturbation);
    /// Gives the volume a generated refractive_index grid (a glass sphere with noise, issue #16),
    /// or removes its grid (nullopt; InvalidArgument when it has none), in a new version; its number.
    int setRefraction(Session& s, const std::optional<core::GlassSphere>& glass);

    // The session's animation (issue #16, docs/ANIMATION.md; session_frames.cpp).
    /// Stores an uploaded VDB as frame n (replacing it); must share the other frames' grid.
    void uploadFrame(Session& s, int n, const std::string& bytes);
    /// Stores every frame of one VDB holding a whole animation (core::loadVdbFrames); their numbers.
    std::vector<int> uploadFrames(Session& s, const std::string& bytes);
    void removeFrame(Session& s, int n);
    std::string downloadFrame(Session& s, int n);
    /// Solves the frames that have views with targets (key frames) jointly, fills every other
    /// frame from them, and stores the results (solved): a job with a progress event per key
    /// frame and sweep.
    std::shared_ptr<Job> startAnimate(const std::shared_ptr<Session>& session, const protocol::AnimateRequest& request);
    /// Renders every frame with one camera to PNG in the job's folder (GET /jobs/{id}/frames/{i}.png).
    std::shared_ptr<Job> startFramesRender(const std::shared_ptr<Session>& session, const protocol::FramesRenderRequest& request);
    void uploadVdb(Session& s, const std::string& bytes);          ///< a new version
    /// The VDB of a version (the current one by default): a stored version's file is sent as it
    /// was written (its size checked). A damaged version answers io_error (422).
    std::string downloadVdb(Session& s, std::optional<int> version);
    /// What the data directory's quarantine holds (empty without one).
    std::vector<QuarantineEntry> quarantine() const;

    // Renders (on the GL thread).
    /// The render (`beauty`), and with `layers` its compositing layers (for EXR answers).
    core::RenderLayers render(Session& s, const core::Camera& camera, bool layers = false);
    core::RenderLayers renderView(Session& s, const std::string& viewId, bool layers = false);
    /// The translucent preview (SPEC §9) of the session's volume under its lighting; `medium`
    /// gets the medium alone (premultiplied, for EXR answers). Under the render budget.
    core::Image renderTranslucent(Session& s, const core::Camera& camera, const core::TranslucentSettings& settings,
                                  core::Image* medium = nullptr);
    /// A view rendered from a running job's latest iterate; after the job, the session's volume.
    core::Image renderPreview(const std::string& jobId, const std::string& viewId);

    // The light-shaft stylizer (session_stylizer.cpp; SPEC §7). Every change moves the
    // stylizer's revision, is on disk before the method returns, and wakes its live streams.
    StylizerSnapshot stylizer(Session& s) const;
    /// Replaces the scene: its meshes and TF resolved against the uploads (ValidationError naming
    /// the fields), its camera within the image-side limit (413).
    StylizerSnapshot setStylizerScene(Session& s, const protocol::StylizerSceneRequest& request);
    /// The scene before the last change (redo: the one undone last); conflict (409) when there is
    /// none or it no longer resolves (a mesh it used was deleted).
    StylizerSnapshot undoStylizer(Session& s, bool redo);
    /// Renders the frame the request's camera sees and reads the pixel's AOVs and occluder.
    StylizerPick pickStylizer(Session& s, const protocol::StylizerPickRequest& request);
    /// Picks the pixel and adds a constraint there with the request's colour to a diffusion layer
    /// of the scene's TF (a TF of layers is made when there is none; an image TF becomes its
    /// first, image layer); an undoable scene change.
    AddedTfConstraint addTfConstraint(Session& s, const protocol::StylizerPickRequest& request);
    std::vector<OccluderMeshInfo> occluderMeshes(Session& s) const;
    /// Reads and stores a mesh file under `name` (422 unreadable, empty or non-finite; 413 over
    /// the upload, vertex or per-session limits); the scene re-renders if it uses `name`.
    OccluderMeshInfo putOccluderMesh(Session& s, const std::string& name, const std::string& bytes);
    void removeOccluderMesh(Session& s, const std::string& name);  ///< busy (409) while the scene uses it
    /// Decodes and stores the TF image (RGB or RGBA, ≤ 4096 a side; 422 otherwise).
    TransferImageInfo setTransferImage(Session& s, const std::string& bytes);
    core::Image transferImage(Session& s) const;   ///< not_found without one
    /// The TF the scene applies (its layers compiled; anchors where they were placed); not_found without one.
    core::Image compiledTransferFunction(Session& s) const;
    void removeTransferImage(Session& s);          ///< busy (409) while the scene uses it
    /// A frame (or AOV) of the session's stylizer on the GL thread; over_budget (422) when its
    /// estimated time is over the render budget.
    core::StylizedFrame stylize(Session& s, const protocol::StylizerFrameRequest& request);
    /// The live stream's next frame: waits up to `wait` for a revision newer than `after`, then
    /// answers the newest revision's frame (rendered once, then kept); nullopt on time-out.
    std::optional<LiveFrame> nextLiveFrame(Session& s, uint64_t after, std::chrono::milliseconds wait);
    /// The kept live frame if it shows `revision` (frames are replaced by newer ones).
    std::optional<LiveFrame> liveFrame(Session& s, uint64_t revision) const;

    // Solve jobs.
    std::shared_ptr<Job> startSolve(const std::shared_ptr<Session>& s, const core::SolveOptions& options);
    std::shared_ptr<Job> job(const std::string& id) const;  ///< ApiError not_found
    /// Renders the stylizer's camera path (or a span of its scene time) as PNG frames, and an MP4
    /// when asked, in a job on the GL thread: a progress event per frame, the files after
    /// (jobFile). Checked before it is queued: the span, the frame count, the per-frame budget.
    std::shared_ptr<Job> startSequence(const std::shared_ptr<Session>& s, const protocol::StylizerSequenceRequest& request);
    /// The path of a file job `jobId` wrote (frame_00000.png, video.mp4); not_found without it.
    std::filesystem::path jobFile(const std::string& jobId, const std::string& name) const;
    void cancel(Job& job) { job.cancel = true; }

    /// For tests that race two edits: called (without the session's lock) between the moment a
    /// volume edit copied the volume and the moment it commits.
    void setVolumeEditHook(std::function<void()> hook) { m_volumeEditHook = std::move(hook); }

private:
    /// On the GL thread: frees every session's GPU copy, every job's preview and the engines.
    void freeGpuObjects();
    void checkUploadSize(const std::string& bytes, const std::string& what) const;
    /// Copies the volume, edits the copy off the lock and commits it as a new version; its number.
    int editVolume(Session& s, const std::function<void(core::Volume&)>& edit);
    /// A volume as the bytes of a VDB file (saveVdb).
    static std::string vdbBytes(const core::Volume& v);
    /// An uploaded VDB read in the child reader (UnsupportedMedia, TooLarge naming "the upload").
    core::Volume readUploadedVdb(const std::string& bytes) const;
    std::map<int, core::Volume> readUploadedVdbFrames(const std::string& bytes) const;
    /// An upload written to a temporary file and read by `read`; its errors name "the upload".
    template <typename T>
    T readUpload(const std::string& bytes, const std::function<T(const std::string&)>& read) const;
    /// Stores frame n (the session locked by the caller): one grid for all frames, at most kMaxFrames.
    void storeFrame(Session& s, int n, core::Volume v);
    /// storeFrame's checks: frame n may join the session's frames (one grid, at most kMaxFrames).
    static void storeFrameChecks(const Session& s, int n, const core::Volume& v);
    void runAnimate(Job& job, Session& s, const protocol::AnimateRequest& q, core::GpuDevice& device);
    /// Makes `volume` the newest version, on disk before it returns. Call with the session's
    /// lock held; returns the stale GPU copy (release() it after unlocking).
    std::shared_ptr<core::GpuVolume> commitVersion(Session& s, core::Volume volume);
    void release(std::shared_ptr<core::GpuVolume> gpu);
    /// not_found if `n` is not a version of `s`, io_error if it is damaged (call with the lock held).
    void checkVersion(const Session& s, int n) const;
    /// A copy of version `n`: the current volume, the older one kept in memory, or read from disk
    /// (without the lock; a file found damaged is quarantined and answers io_error).
    core::Volume olderVersion(Session& s, int n);
    /// Quarantines version `n`'s file and lists it as damaged.
    void recordDamage(Session& s, int n, const std::string& reason);
    core::RenderLayers renderOnGl(Session& s, const core::Camera& camera, const core::Lighting& lighting, bool layers);
    /// On the GL thread: renders `gpu` under the render budget.
    core::RenderLayers renderBudgeted(core::GpuDevice& device, core::GpuVolume& gpu, const core::Camera& camera,
                                      const core::Lighting& lighting, bool layers);
    /// On the GL thread, with the session's lock held: the session's GPU copy, uploaded if there
    /// is none (not_found once removed). Shared, so a render can drop the lock and keep it alive.
    std::shared_ptr<core::GpuVolume> sessionGpu(Session& s);
    /// On the GL thread: sessionGpu() under the session's lock, released before any GL work.
    std::shared_ptr<core::GpuVolume> lockedSessionGpu(Session& s);
    /// The session's lighting with the view's plate, if it has one.
    core::Lighting viewLighting(Session& s, const SessionView& v);
    /// On the GL thread: the one renderer of the service (created on first use).
    core::Renderer& renderer(core::GpuDevice& device);
    /// On the GL thread: frees the preview copies of the session's finished jobs.
    void dropPreviews(const Session& s);
    /// Throws not_found if `s` was deleted; else writes it (call with its lock held).
    void saved(Session& s);
    void saved(const Job& j);
    /// Forgets the oldest finished jobs beyond ServiceLimits::finishedJobsKept: memory, record
    /// on disk, the id in its session's list, and its preview copy (freed on the GL thread).
    void pruneJobs();

    // The solve job on the GL thread (solve_job.cpp).
    void runSolve(const std::shared_ptr<Job>& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options,
                  core::GpuDevice& device);
    void solveAndCommit(Job& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options, core::GpuDevice& device);
    /// "unknowns": ["lights", …]: the environment lobes (and the volume's unknowns in turn); the
    /// session's lighting gets the solved radiances (and the volume a new version).
    void solveLightsAndCommit(Job& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options, core::GpuDevice& device);
    /// Runs `work` as the job's body: cancelled before it starts, or running (recorded) until it
    /// returns (it sets the result and done) or throws (failed or cancelled, with the error).
    void runJob(Job& job, const std::function<void()>& work);
    void finishJob(Job& job);
    /// A new job of session `s` (too_many_jobs at its queue limit), recorded and listed.
    std::shared_ptr<Job> queueJob(Session& s);
    void checkJobQueue(const Session& s) const;  ///< too_many_jobs at the session's queue limit
    /// Where a job's files go: its folder in the data directory, or in m_scratch.
    std::filesystem::path jobFilesDir(const std::string& jobId) const;
    /// The sequence job on the GL thread (stylizer_sequence.cpp).
    void runSequence(Job& job, const core::StylizerScene& scene, const std::vector<double>& times,
                     const protocol::StylizerSequenceRequest& request, core::GpuDevice& device);

    /// Writes the stylizer's scene, moves its revision and wakes its streams (the lock held).
    /// `history`: the undo/redo stacks changed too (written apart from the scene).
    void stylizerChanged(Session& s, bool history = false);
    /// 413 when a camera of the scene (or of its key frames) is over the image-side limit.
    void checkStylizerCameras(const core::StylizerScene& scene) const;
    /// Makes `scene` the session's (validated; the one before pushed for undo when it is a step,
    /// not a change of time alone), writes it and wakes the streams. The session's lock held.
    StylizerSnapshot commitStylizerScene(Session& s, core::StylizerScene scene, std::vector<std::string> meshRefs);
    /// The pixel `q` names in `scene` (the session's, before the request's camera and time).
    StylizerPick pickIn(const core::StylizerScene& scene, const protocol::StylizerPickRequest& q);
    /// On the GL thread: the one stylizer of the service (created on first use).
    core::Stylizer& stylizerEngine(core::GpuDevice& device);
    core::StylizedFrame stylizeOnGl(const core::StylizerScene& scene, const core::StylizeSettings& settings);
    /// This device's stylizer speed (lookups per second) for frame estimates: measured on the GL
    /// thread when the stylizer first starts, never below kMinStylizerLookupsPerSecond.
    double stylizerLookupsPerSecond();
    /// Seconds a stylizer frame of `scene` with `settings` is estimated to hold the GL thread.
    double stylizerSeconds(const core::StylizerScene& scene, const core::StylizeSettings& settings);

    /// A slot of m_decodeSlots, held while an upload's pixels are decoded.
    struct DecodeSlot {
        explicit DecodeSlot(std::counting_semaphore<>& s) : slots(s) { slots.acquire(); }
        ~DecodeSlot() { slots.release(); }
        std::counting_semaphore<>& slots;
    };
    static constexpr int kConcurrentDecodes = 2;
    std::counting_semaphore<> m_decodeSlots{kConcurrentDecodes};

    ServiceLimits m_limits;
    MemoryBudget m_memory{m_limits.memory};
    std::unique_ptr<core::Renderer> m_renderer;  ///< GL thread only
    std::unique_ptr<core::Stylizer> m_stylizer;  ///< GL thread only
    std::unique_ptr<core::TranslucentRenderer> m_translucent;  ///< GL thread only; created on first use
    std::unique_ptr<core::SolveCache> m_solveCache;  ///< GL thread only; created by the first solve
    SessionStore m_sessions;
    JobStore m_jobs;
    std::mutex m_jobRecords;  ///< orders writing a job's record against forgetting it
    std::unique_ptr<Persistence> m_persist;  ///< null: in memory only
    std::filesystem::path m_scratch;          ///< job files without a data directory (removed at exit)
    std::unique_ptr<GlExecutor> m_gl;
    std::function<void()> m_volumeEditHook;
    std::once_flag m_stylizerSpeedOnce;
    double m_stylizerLookupsPerSecond = 0;
};

}  // namespace volstyle::server

#pragma once
/// \file volume_service.h
/// A session's volume and its animation's frames: versions (revert, edits, uploads, downloads),
/// frames, renders and previews (SPEC §3, docs/ANIMATION.md).

#include "server/service/service_context.h"

namespace volstyle::server {

class VolumeService {
public:
    explicit VolumeService(ServiceContext& ctx) : m_ctx(ctx) {}

    // Volume versions (session_volume.cpp).
    int revert(Session& s, int version);  ///< the new version number
    /// One step back (or forward: redo) through what the session showed: a new version with the
    /// content of the version before the last edit, undo or redo; its number. 409 with nothing
    /// to undo (redo).
    int step(Session& s, bool redo);
    /// Bakes the perturbation (core/translucent/perturbation.h) into a new version; its number.
    int perturb(Session& s, const core::Perturbation& perturbation);
    /// Gives the volume a generated refractive_index grid (a glass sphere with noise, issue #16),
    /// or removes its grid (nullopt; InvalidArgument when it has none), in a new version; its number.
    int setRefraction(Session& s, const std::optional<core::GlassSphere>& glass);
    void uploadVdb(Session& s, const std::string& bytes);  ///< a new version
    /// The VDB of a version (the current one by default): a stored version's file is sent as it
    /// was written (its size checked). A damaged version answers io_error (422). Its tag is the
    /// session and version (a VDB's bytes differ on every write: OpenVDB stamps a new UUID).
    VdbDownload downloadVdb(Session& s, std::optional<int> version);

    // The session's animation (issue #16, docs/ANIMATION.md; session_frames.cpp).
    /// Stores an uploaded VDB as frame n (replacing it); must share the other frames' grid.
    void uploadFrame(Session& s, int n, const std::string& bytes);
    /// Stores every frame of one VDB holding a whole animation (core::loadVdbFrames); their numbers.
    std::vector<int> uploadFrames(Session& s, const std::string& bytes);
    void removeFrame(Session& s, int n);
    /// Frame n's VDB; its tag is a hash of the frame's voxels.
    VdbDownload downloadFrame(Session& s, int n);
    /// Solves the frames that have views with targets (key frames) jointly, fills every other
    /// frame from them, and stores the results (solved): a job with a progress event per key
    /// frame and sweep.
    std::shared_ptr<Job> startAnimate(const std::shared_ptr<Session>& session, const protocol::AnimateRequest& request,
                                      const JobOrigin& origin = {});
    /// Renders every frame with one camera to PNG in the job's folder (GET /jobs/{id}/frames/{i}.png).
    std::shared_ptr<Job> startFramesRender(const std::shared_ptr<Session>& session, const protocol::FramesRenderRequest& request,
                                           const JobOrigin& origin = {});

    // Renders on the GL thread (session_render.cpp).
    /// The render (`beauty`), and with `layers` its compositing layers (for EXR answers).
    core::RenderLayers render(Session& s, const core::Camera& camera, bool layers = false);
    core::RenderLayers renderView(Session& s, const std::string& viewId, bool layers = false);
    /// The translucent preview (SPEC §9) of the session's volume under its lighting; `medium`
    /// gets the medium alone (premultiplied, for EXR answers). Under the render budget.
    core::Image renderTranslucent(Session& s, const core::Camera& camera, const core::TranslucentSettings& settings,
                                  core::Image* medium = nullptr);
    /// A view rendered from a running job's latest iterate; after the job, the session's volume.
    core::Image renderPreview(const std::string& jobId, const std::string& viewId);

    /// For tests that race two edits: called (without the session's lock) between the moment a
    /// volume edit copied the volume and the moment it commits.
    void setVolumeEditHook(std::function<void()> hook) { m_volumeEditHook = std::move(hook); }

private:
    /// Copies the volume, edits the copy off the lock and commits it as a new version unless
    /// another change committed meanwhile (409); its number.
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
    /// The session's lighting with the view's plate, if it has one.
    core::Lighting viewLighting(Session& s, const SessionView& v);

    ServiceContext& m_ctx;
    std::function<void()> m_volumeEditHook;
};

}  // namespace volstyle::server

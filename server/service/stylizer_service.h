#pragma once
/// \file stylizer_service.h
/// A session's light-shaft stylizer (SPEC §7): its scene (undo, redo), occluder meshes and
/// transfer-function image, picks and clicked constraints, frames and the live stream, and
/// sequences. Every change moves the stylizer's revision, is on disk before the method returns,
/// and wakes its live streams.

#include "server/service/live_stream_pipeline.h"
#include "server/service/service_context.h"

namespace volstyle::server {

class StylizerService {
public:
    explicit StylizerService(ServiceContext& ctx) : m_ctx(ctx) {}

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
    /// first, image layer); an undoable scene change, refused (409) if the scene moved since the pick.
    AddedTfConstraint addTfConstraint(Session& s, const protocol::StylizerPickRequest& request);
    std::vector<OccluderMeshInfo> occluderMeshes(Session& s) const;
    /// Reads and stores a mesh file under `name` (422 unreadable, empty or non-finite; 413 over
    /// the upload, vertex or per-session limits); the scene re-renders if it uses `name`.
    OccluderMeshInfo putOccluderMesh(Session& s, const std::string& name, const std::string& bytes);
    void removeOccluderMesh(Session& s, const std::string& name);  ///< busy (409) while the scene uses it
    /// Decodes and stores the TF image (RGB or RGBA, ≤ 4096 a side; 422 otherwise).
    TransferImageInfo setTransferImage(Session& s, const std::string& bytes);
    core::Image transferImage(Session& s) const;  ///< not_found without one
    /// The TF the scene applies (its layers compiled; anchors where they were placed); not_found without one.
    core::Image compiledTransferFunction(Session& s) const;
    void removeTransferImage(Session& s);  ///< busy (409) while the scene uses it
    /// A frame (or AOV) of the session's stylizer on the GL thread; over_budget (422) when its
    /// estimated time is over the render budget.
    core::StylizedFrame stylize(Session& s, const protocol::StylizerFrameRequest& request);
    /// The live stream's next frame: the one `pipeline` rendered while the last was sent, else,
    /// after waiting up to `wait` for a revision newer than `after`, the newest revision's frame
    /// (rendered once, then kept; nullopt on time-out). Before encoding it, the render of a newer
    /// revision starts (issue #40: encoding overlaps the next frame's render and read-back).
    std::optional<LiveFrame> nextLiveFrame(LiveStreamPipeline& pipeline, uint64_t after, std::chrono::milliseconds wait);
    /// A stream's pipeline for `s`: frames come back through its read-back slots.
    std::unique_ptr<LiveStreamPipeline> liveStreamPipeline(std::shared_ptr<Session> s) const;
    /// The kept live frame if it shows `revision` (frames are replaced by newer ones).
    std::optional<LiveFrame> liveFrame(Session& s, uint64_t revision) const;
    /// Renders the stylizer's camera path (or a span of its scene time) as PNG frames, and an MP4
    /// when asked, in a job on the GL thread: a progress event per frame, the files after
    /// (JobService::jobFile). Checked before it is queued: the span, the frame count, the per-frame budget.
    std::shared_ptr<Job> startSequence(const std::shared_ptr<Session>& s, const protocol::StylizerSequenceRequest& request,
                                       const JobOrigin& origin = {});

private:
    /// 413 when a camera of the scene (or of its key frames) is over the image-side limit.
    void checkStylizerCameras(const core::StylizerScene& scene) const;
    /// Makes `scene` the session's (validated; the one before pushed for undo when it is a step,
    /// not a change of time alone), writes it and wakes the streams. The session's lock held.
    StylizerSnapshot commitStylizerScene(Session& s, core::StylizerScene scene, std::vector<std::string> meshRefs);
    /// The pixel `q` names in `scene` (the session's, before the request's camera and time).
    StylizerPick pickIn(Session& s, const core::StylizerScene& scene, const protocol::StylizerPickRequest& q);
    core::StylizedFrame stylizeOnGl(Session& s, const core::StylizerScene& scene, const core::StylizeSettings& settings);
    /// Checks the frame's budget, then queues the live frame of `snapshot` on the GL thread.
    std::future<RenderedLiveFrame> startLiveFrame(LiveStreamPipeline& pipeline, const StylizerSnapshot& snapshot);
    /// Throws over_budget when a frame of `scene` is estimated over the render budget.
    void checkRenderBudget(const core::StylizerScene& scene, const core::StylizeSettings& settings);
    /// This device's stylizer speed (lookups per second) for frame estimates: measured on the GL
    /// thread when the stylizer first starts, never below kMinStylizerLookupsPerSecond.
    double stylizerLookupsPerSecond();
    /// Seconds a stylizer frame of `scene` with `settings` is estimated to hold the GL thread.
    double stylizerSeconds(const core::StylizerScene& scene, const core::StylizeSettings& settings);
    /// The sequence job on the GL thread (stylizer_sequence.cpp).
    void runSequence(Job& job, Session& session, const core::StylizerScene& scene, const std::vector<double>& times,
                     const protocol::StylizerSequenceRequest& request, core::GpuDevice& device);

    ServiceContext& m_ctx;
    std::once_flag m_stylizerSpeedOnce;
    double m_stylizerLookupsPerSecond = 0;
};

}  // namespace volstyle::server

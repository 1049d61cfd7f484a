// A stylizer sequence job (issue #15): the scene's camera path, or a span of its time, rendered
// frame by frame on the GL thread into the job's folder as PNG (frame_00000.png, …), then encoded
// as MP4 by ffmpeg when asked. A progress event per frame; requests waiting for the GL thread run
// between frames; cancel stops at the next frame.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/stylize/keyframes.h"
#include "core/stylize/stylizer.h"
#include "core/stylize/stylizer_files.h"
#include "server/service/services.h"
#include "server/runtime/video_encoder.h"

namespace volstyle::server {
namespace {

/// A sequence's frames at most: 10 minutes at 24 fps; and its pixels, all frames together (about
/// 1,000 frames of 1920×1080, a few GB of PNG on disk).
constexpr size_t kMaxSequenceFrames = 14400;
constexpr double kMaxSequencePixels = 2.0e9;

}  // namespace

std::shared_ptr<Job> StylizerService::startSequence(const std::shared_ptr<Session>& session, const protocol::StylizerSequenceRequest& q,
                                                    const JobOrigin& origin) {
    const core::StylizerScene scene = stylizer(*session).scene;
    const auto [first, last] = core::pathSpan(scene.keyframes);
    if (scene.keyframes.empty() && !q.end)
        throw ApiError(ErrorCode::InvalidArgument, "the scene has no key frames: give the sequence an end time",
                       {{"/end", "is required without key frames"}});
    std::vector<double> times;
    try {
        times = core::sequenceTimes(q.start.value_or(scene.keyframes.empty() ? scene.time : first), q.end.value_or(last), q.fps,
                                    kMaxSequenceFrames);
        core::checkPathCameras(scene, times);
    } catch (const InvalidArgument& e) {
        throw ApiError(ErrorCode::InvalidArgument, std::string("the sequence: ") + e.what(), {{"/end", e.what()}});
    }
    const core::Camera& cam = scene.keyframes.empty() ? scene.camera : scene.keyframes.front().camera;  // a path's size
    const double pixels = double(times.size()) * cam.width * cam.height;
    if (pixels > kMaxSequencePixels)
        throw ApiError(ErrorCode::TooLarge,
                       fmt::format("the sequence would be {} frames of {}×{} ({:.1e} pixels), over the limit of {:.0e}: use a lower "
                                   "fps, a shorter span or a smaller camera",
                                   times.size(), cam.width, cam.height, pixels, kMaxSequencePixels),
                       {{"/fps", "too many pixels in all"}});
    if (q.video && findFfmpeg().empty())
        throw ApiError(ErrorCode::InvalidArgument, "this server has no ffmpeg to encode a video; ask for the frames alone",
                       {{"/video", "no ffmpeg on the server"}});
    // Each frame holds the GL thread like a POST …/frame: the same budget, checked per frame now.
    const double seconds = stylizerSeconds(core::sceneAtTime(scene, times.front()), q.settings);
    if (m_ctx.limits.renderBudgetSeconds > 0 && seconds > m_ctx.limits.renderBudgetSeconds)
        throw ApiError(ErrorCode::OverBudget, fmt::format("each frame would take about {:.0f} s, over the render budget of {:g} s; use fewer "
                                                          "pixels or a smaller shadow map",
                                                          seconds, m_ctx.limits.renderBudgetSeconds));
    auto job = m_ctx.queueJob(*session, origin);
    m_ctx.gl->submit([this, job, session, scene, times, q](core::GpuDevice& device) {
        m_ctx.runJob(*job, [&] { runSequence(*job, *session, scene, times, q, device); });
        m_ctx.finishJob(*job);
    });
    return job;
}

void StylizerService::runSequence(Job& job, Session& session, const core::StylizerScene& scene, const std::vector<double>& times,
                                 const protocol::StylizerSequenceRequest& q, core::GpuDevice& device) {
    const std::filesystem::path dir = m_ctx.jobFilesDir(job.id);
    std::filesystem::create_directories(dir);
    const core::SaveOptions save = core::stylizerSaveOptions(q.output, q.exposure);
    core::StylizeSettings settings = q.settings;
    core::readBackOnly(settings, q.output);
    protocol::SequenceJobResult result{times.size(), q.fps, times.front(), times.back(), 0, {}, std::nullopt};
    // A heterogeneous medium is the session's volume on the GPU, as the job found it.
    const std::shared_ptr<core::GpuVolume> medium = scene.volume ? m_ctx.lockedSessionGpu(session) : nullptr;
    for (size_t i = 0; i < times.size(); ++i) {
        if (job.cancel) throw ApiError(ErrorCode::Cancelled, fmt::format("cancelled after {} of {} frames", i, times.size()));
        const core::StylizedFrame f = m_ctx.stylizerEngine(device).render(core::sceneAtTime(scene, times[i]), settings, medium.get());
        const std::string name = sequenceFrameName(i);
        core::saveImage((dir / name).string(), f.output(q.output), save);
        result.renderMs += f.totalMs;
        result.frameUrls.push_back(jobFileUrl(job.id, "frames/" + std::to_string(i) + ".png"));
        job.report(protocol::SequenceJobProgress{i + 1, times.size(), times[i], f.totalMs, result.frameUrls.back()});
        m_ctx.gl->runShortTasks(device);  // frames and renders other clients wait for
    }
    if (q.video) {
        encodeVideo(dir, times.size(), q.fps, dir / "video.mp4");
        result.videoUrl = jobFileUrl(job.id, "video.mp4");
    }
    spdlog::info("job {}: {} frames{}", job.id, times.size(), q.video ? " and a video" : "");
    std::lock_guard lock(job.mutex);
    job.state = JobState::Done;
    job.result = std::move(result);
}

}  // namespace volstyle::server

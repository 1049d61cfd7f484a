// The session's animation (issue #16, docs/ANIMATION.md): frames uploaded as VDBs, views tied to
// frames, the key-frame solve as a job (core/solve/keyframe_solver.h) and a job rendering every
// frame to PNG.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/base/content_hash.h"
#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/solve/keyframe_solver.h"
#include "core/volume/vdb_io.h"
#include "server/store/persistence.h"
#include "server/service/services.h"
#include "server/runtime/video_encoder.h"

namespace volstyle::server {
namespace {

/// An animation's frames at most (each a volume in memory).
constexpr size_t kMaxFrames = 1000;

SessionFrame& frameOf(Session& s, int n) {
    auto it = s.frames.find(n);
    if (it == s.frames.end()) throw ApiError(ErrorCode::NotFound, "the session has no frame " + std::to_string(n));
    return it->second;
}

/// Frames put on one brick layout (sparse animations) must still fit: the layout, the union of
/// every frame's bricks, within the volume limits, and the frames, with the solved grid, within
/// the session's memory budget. Checked before the solve and again before storing its result.
void checkFramesFit(const MemoryBudget& memory, const core::VolumeLimits& limits, Session& s, const std::map<int, core::Volume>& frames,
                    bool albedo) {
    if (frames.empty()) return;
    if (const core::BrickLayout* b = frames.begin()->second.bricks()) {
        try {
            core::checkSparseLimits(b->dims(), b->activeBricks(), b->slots(), 3, limits);
        } catch (const LimitExceeded& e) {
            throw LimitExceeded(std::string("the frames on one brick layout (the union of their bricks): ") + e.what());
        }
    }
    std::lock_guard lock(s.mutex);
    size_t adding = 0, freeing = 0;
    for (const auto& [n, v] : frames) {
        if (!s.frames.count(n)) continue;
        adding += v.memoryBytes() + ((albedo ? v.hasAlbedo() : v.hasEmission()) ? 0 : 12 * v.storedVoxels());  // the solved grid
        freeing += s.frames.at(n).volume.memoryBytes();
    }
    memory.check(s, adding, freeing, fmt::format("the animation's {} frames, solved", frames.size()));
}

}  // namespace

void VolumeService::uploadFrame(Session& s, int n, const std::string& bytes) {
    if (n < 0 || n > protocol::kMaxFrameNumber)
        throw ApiError(ErrorCode::InvalidArgument, "frame numbers are in [0, " + std::to_string(protocol::kMaxFrameNumber) + "]");
    core::Volume v = readUploadedVdb(bytes);
    core::velocityOf(v);  // a velocity grid that cannot be read is refused now, not in the solve
    std::lock_guard lock(s.mutex);
    storeFrame(s, n, std::move(v));
    m_ctx.saved(s);
}

std::vector<int> VolumeService::uploadFrames(Session& s, const std::string& bytes) {
    std::map<int, core::Volume> frames = readUploadedVdbFrames(bytes);
    for (auto& [n, v] : frames) {
        if (n < 0 || n > protocol::kMaxFrameNumber)
            throw ApiError(ErrorCode::InvalidArgument, "frame numbers are in [0, " + std::to_string(protocol::kMaxFrameNumber) + "]");
        core::velocityOf(v);
    }
    std::vector<int> numbers;
    std::lock_guard lock(s.mutex);
    // All or nothing: every frame is checked (against the session's frames and the file's first)
    // before any is stored.
    size_t added = 0;
    for (const auto& [n, v] : frames) {
        storeFrameChecks(s, n, v);
        if (!(v.dims() == frames.begin()->second.dims()) || !(v.worldFromIndex() == frames.begin()->second.worldFromIndex()))
            throw ApiError(ErrorCode::InvalidArgument, fmt::format("frames {} and {} of the file lie on different grids: an animation's frames "
                                                                   "share one grid (dims and transform); resample them first",
                                                                   frames.begin()->first, n));
        added += s.frames.count(n) ? 0 : 1;
    }
    if (s.frames.size() + added > kMaxFrames)
        throw ApiError(ErrorCode::TooLarge, fmt::format("the session would hold {} frames, over the limit of {}", s.frames.size() + added, kMaxFrames));
    size_t adding = 0, freeing = 0;
    for (const auto& [n, v] : frames) {
        adding += v.memoryBytes();
        if (s.frames.count(n)) freeing += s.frames.at(n).volume.memoryBytes();
    }
    m_ctx.memory.check(s, adding, freeing, fmt::format("the file's {} frames", frames.size()));
    for (auto& [n, v] : frames) {
        numbers.push_back(n);
        storeFrame(s, n, std::move(v));
    }
    m_ctx.saved(s);
    return numbers;
}

void VolumeService::storeFrame(Session& s, int n, core::Volume v) {
    storeFrameChecks(s, n, v);
    m_ctx.memory.check(s, v.memoryBytes(), s.frames.count(n) ? s.frames.at(n).volume.memoryBytes() : 0, "frame " + std::to_string(n));
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    if (m_ctx.persist) m_ctx.persist->saveFrame(s.id, n, v);
    s.frames[n] = {std::move(v), false};
}

void VolumeService::storeFrameChecks(const Session& s, int n, const core::Volume& v) {
    if (!s.frames.count(n) && s.frames.size() >= kMaxFrames)
        throw ApiError(ErrorCode::TooLarge, "the session holds " + std::to_string(kMaxFrames) + " frames already");
    for (const auto& [m, f] : s.frames)
        if (m != n && (!(f.volume.dims() == v.dims()) || !(f.volume.worldFromIndex() == v.worldFromIndex())))
            throw ApiError(ErrorCode::InvalidArgument,
                           fmt::format("frame {} is {}x{}x{} on another grid than frame {} ({}x{}x{}): an animation's frames share one grid "
                                       "(dims and transform); resample them first",
                                       n, v.dims().x, v.dims().y, v.dims().z, m, f.volume.dims().x, f.volume.dims().y, f.volume.dims().z));
}

void VolumeService::removeFrame(Session& s, int n) {
    std::lock_guard lock(s.mutex);
    frameOf(s, n);
    s.frames.erase(n);
    if (m_ctx.persist) m_ctx.persist->removeFrame(s.id, n);
    m_ctx.saved(s);
}

VdbDownload VolumeService::downloadFrame(Session& s, int n) {
    core::Volume v;
    {
        std::lock_guard lock(s.mutex);
        v = frameOf(s, n).volume;
    }
    uint64_t hash = 0;
    for (const std::vector<float>* grid : {&v.extinction(), &v.albedo(), &v.emission()})
        hash ^= contentHash(std::string_view(reinterpret_cast<const char*>(grid->data()), grid->size() * sizeof(float))) + 0x9e3779b97f4a7c15ull + (hash << 6);
    return {vdbBytes(v), fmt::format("{}-f{}-{:016x}", s.id, n, hash)};
}

std::shared_ptr<Job> VolumeService::startAnimate(const std::shared_ptr<Session>& session, const protocol::AnimateRequest& q,
                                                 const JobOrigin& origin) {
    {
        std::lock_guard lock(session->mutex);
        if (session->frames.empty()) throw ApiError(ErrorCode::InvalidArgument, "the session has no frames: PUT …/frames/{n} first");
        bool anyKey = false;
        for (const auto& v : session->views.list)
            if (v.frame && v.target) {
                if (!session->frames.count(*v.frame))
                    throw ApiError(ErrorCode::InvalidArgument, "view '" + v.id + "' is on frame " + std::to_string(*v.frame) + ", which the session does not have");
                anyKey = true;
            }
        if (!anyKey) throw ApiError(ErrorCode::InvalidArgument, "no view of a frame has a target: add views with \"frame\" and paint them");
    }
    auto job = m_ctx.queueJob(*session, origin);
    m_ctx.gl->submit([this, job, session, q](core::GpuDevice& device) {
        m_ctx.runJob(*job, [&] { runAnimate(*job, *session, q, device); });
        m_ctx.finishJob(*job);
    });
    return job;
}

void VolumeService::runAnimate(Job& job, Session& s, const protocol::AnimateRequest& q, core::GpuDevice& device) {
    // The key frames: the frames with painted views (copied under the lock; solved off it).
    std::vector<core::KeyFrame> keys;
    std::map<int, core::Volume> frames;
    core::Lighting lighting;
    {
        std::lock_guard lock(s.mutex);
        lighting = s.light.lighting;
        for (const auto& [n, f] : s.frames) frames[n] = f.volume;
        std::map<int, std::vector<core::SolveView>> views;
        for (const auto& v : s.views.list)
            if (v.frame && v.target && s.frames.count(*v.frame)) views[*v.frame].push_back({v.id, v.camera, *v.target, v.weights, v.background});
        for (auto& [n, list] : views) keys.push_back({n, {}, std::move(list), {}});
    }
    // Sparse frames on one layout, so that values carry from frame to frame brick for brick.
    std::vector<core::Volume*> all;
    for (auto& [n, v] : frames) all.push_back(&v);
    core::putFramesOnOneLayout(all, {}, q.albedo ? core::Unknown::Albedo : core::Unknown::Emission);
    checkFramesFit(m_ctx.memory, m_ctx.limits.volumeLimits, s, frames, q.albedo);
    for (auto& k : keys) {
        k.volume = frames[k.frame];
        k.velocity = core::velocityOf(k.volume);
        for (float& x : k.velocity) x = float(x / q.fps);
    }
    core::KeyFrameOptions o;
    o.solve.unknown = q.albedo ? core::Unknown::Albedo : core::Unknown::Emission;
    o.solve.maxIterations = q.maxIterations;
    o.temporal = q.temporal;
    o.sweeps = q.sweeps;
    o.followFlow = q.followFlow;
    core::KeyFrameReport report;
    int steps = 0;
    const int total = q.sweeps * int(keys.size());
    const auto solved = core::solveKeyFrames(device, keys, lighting, o, &report, [&](int sweep, int k) {
        if (job.cancel) throw ApiError(ErrorCode::Cancelled, fmt::format("cancelled at sweep {} of {}", sweep + 1, q.sweeps));
        job.report(protocol::AnimateJobProgress{sweep + 1, q.sweeps, keys[size_t(k)].frame, ++steps, total});
        m_ctx.gl->runShortTasks(device);
    });
    // Every frame from the key frames, stored (and written) as solved.
    for (auto& [n, v] : frames)
        (q.albedo ? v.ensureAlbedo() : v.ensureEmission()) = core::frameFromKeys(keys, solved, o.solve.unknown, n, o.followFlow);
    checkFramesFit(m_ctx.memory, m_ctx.limits.volumeLimits, s, frames, q.albedo);
    protocol::AnimateJobResult result{{}, {}, report.change};
    for (const auto& k : keys) result.keyFrames.push_back(k.frame);
    {
        std::lock_guard lock(s.mutex);
        for (auto& [n, v] : frames) {
            if (!s.frames.count(n)) continue;  // removed while the job ran
            if (m_ctx.persist && !s.removed) m_ctx.persist->saveFrame(s.id, n, v);
            s.frames[n] = {std::move(v), true};
            result.frames.push_back(n);
        }
        if (!s.removed) m_ctx.saved(s);
    }
    spdlog::info("job {}: {} key frames solved, {} frames stored", job.id, keys.size(), result.frames.size());
    std::lock_guard lock(job.mutex);
    job.state = JobState::Done;
    job.result = std::move(result);
}

std::shared_ptr<Job> VolumeService::startFramesRender(const std::shared_ptr<Session>& session, const protocol::FramesRenderRequest& q,
                                                      const JobOrigin& origin) {
    {
        std::lock_guard lock(session->mutex);
        if (session->frames.empty()) throw ApiError(ErrorCode::InvalidArgument, "the session has no frames: PUT …/frames/{n} first");
    }
    auto job = m_ctx.queueJob(*session, origin);
    m_ctx.gl->submit([this, job, session, q](core::GpuDevice& device) {
        m_ctx.runJob(*job, [&] {
            std::map<int, core::Volume> frames;
            core::Lighting lighting;
            {
                std::lock_guard lock(session->mutex);
                for (const auto& [n, f] : session->frames) frames[n] = f.volume;
                lighting = session->light.lighting;
            }
            const std::filesystem::path dir = m_ctx.jobFilesDir(job->id);
            std::filesystem::create_directories(dir);
            core::Renderer renderer(device);
            core::SaveOptions save;
            save.exposure = q.exposure;
            protocol::FramesRenderJobResult result;
            size_t i = 0;
            for (const auto& [n, v] : frames) {
                if (job->cancel) throw ApiError(ErrorCode::Cancelled, fmt::format("cancelled after {} of {} frames", i, frames.size()));
                core::GpuVolume gpu(v);
                // Each frame under the render budget, and a cancel stops it within a chunk of its
                // march (three 4096² frames once ran 360 s, deaf to a cancel at 300 s).
                const WorkBudget budget(m_ctx.limits.renderBudgetSeconds, &job->cancel);
                core::Image picture;
                try {
                    picture = renderer.render(gpu, q.camera, lighting, {}, nullptr, budget);
                } catch (const Cancelled&) {
                    throw ApiError(ErrorCode::Cancelled, fmt::format("cancelled during frame {} ({} of {} done)", n, i, frames.size()));
                } catch (const OverBudget& e) {
                    throw ApiError(ErrorCode::OverBudget, fmt::format("frame {}: {}", n, e.what()));
                }
                core::saveImage((dir / sequenceFrameName(i)).string(), picture, save);
                result.frameUrls.push_back(jobFileUrl(job->id, "frames/" + std::to_string(i) + ".png"));
                result.frames.push_back(n);
                job->report(protocol::FramesRenderJobProgress{n, i + 1, frames.size(), result.frameUrls.back()});
                m_ctx.gl->runShortTasks(device);
                ++i;
            }
            std::lock_guard lock(job->mutex);
            job->state = JobState::Done;
            job->result = std::move(result);
        });
        m_ctx.finishJob(*job);
    });
    return job;
}

}  // namespace volstyle::server

// A solve job on the GL thread: snapshot the session, solve with progress and previews, commit
// the result as a new version, record the final state (SessionService, SPEC §3 jobs).
#include <spdlog/spdlog.h>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/solve/combined_solve.h"
#include "core/solve/light_solver.h"
#include "core/solve/solve_cache.h"
#include "core/solve/solver.h"
#include "protocol/error_body.h"
#include "protocol/render_json.h"
#include "protocol/solve_json.h"
#include "server/service/session_service.h"

namespace volstyle::server {
namespace {

using protocol::JobEvent;
using protocol::JobState;

/// Previews are announced at most this often: each costs a download and an upload of the iterate.
constexpr auto kPreviewInterval = std::chrono::seconds(1);

/// A copy of what the solve reads, so the session can change (or be read) while it runs.
struct SolveInputs {
    core::Volume volume;
    core::Lighting lighting;
    std::vector<core::SolveView> views;
    std::vector<std::string> viewIds;
};

SolveInputs snapshot(Session& s) {
    std::lock_guard lock(s.mutex);
    SolveInputs in{s.volume, s.lighting, {}, {}};
    for (const auto& v : s.views) {
        if (v.frame) continue;  // a frame of the animation: POST …/animate solves it
        in.viewIds.push_back(v.id);
        in.views.push_back({v.id, v.camera, v.target.value_or(core::Image()), v.weights, v.background});
    }
    return in;
}

}  // namespace

void SessionService::runSolve(const std::shared_ptr<Job>& job, const std::shared_ptr<Session>& s,
                              const core::SolveOptions& options, core::GpuDevice& device) {
    {
        std::lock_guard lock(s->mutex);
        dropPreviews(*s);  // earlier jobs' last iterates: this job's previews replace them
    }
    runJob(*job, [&] { solveAndCommit(*job, s, options, device); });
    std::shared_ptr<core::GpuVolume> preview;  // freed here, on the GL thread, when the job is done
    {
        std::lock_guard lock(job->mutex);
        if (job->state == JobState::Done) preview = std::move(job->preview);
    }
    finishJob(*job);
}

void SessionService::solveAndCommit(Job& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options,
                                    core::GpuDevice& device) {
    if (options.lights.solve) return solveLightsAndCommit(job, s, options, device);
    SolveInputs in = snapshot(*s);
    // Every view a stroke left alone keeps its rows of W and renders from the last solve.
    if (!m_solveCache && m_limits.solveCacheBytes > 0) m_solveCache = std::make_unique<core::SolveCache>(m_limits.solveCacheBytes);
    core::Solver solver(device, in.volume, in.lighting, std::move(in.views), options, m_solveCache.get());
    auto lastPreview = Clock::now() - std::chrono::hours(1);
    core::SolveResult result = solver.run(
        [&](const core::SolveProgress& p) {
            nlohmann::json progress = protocol::solveProgressToJson(p);
            {
                std::lock_guard lock(job.mutex);
                job.progress = progress;
            }
            job.emit(JobEvent::Progress, progress);
            if (Clock::now() - lastPreview >= kPreviewInterval) {
                // The latest iterate in the job's one GPU copy (its extinction is unchanged for
                // emission and albedo solves, so its light volumes stay cached).
                lastPreview = Clock::now();
                std::shared_ptr<core::GpuVolume> preview;
                {
                    std::lock_guard lock(job.mutex);
                    preview = job.preview;
                }
                if (preview) preview->upload(solver.currentVolume());
                else preview = std::make_shared<core::GpuVolume>(solver.currentVolume());
                nlohmann::json urls = nlohmann::json::object();
                for (const auto& id : in.viewIds) urls[id] = "/api/v1/jobs/" + job.id + "/preview/" + id + ".png";
                {
                    std::lock_guard lock(job.mutex);
                    job.preview = std::move(preview);
                }
                job.emit(JobEvent::Preview, {{"iteration", p.iteration}, {"urls", urls}});
            }
            m_gl->runShortTasks(device);  // renders waiting for the GL thread run between iterations
        },
        &job.cancel);
    int version = 0;
    std::shared_ptr<core::GpuVolume> stale;  // freed here, on the GL thread
    {
        std::lock_guard lock(s->mutex);
        stale = commitVersion(*s, std::move(result.volume));  // on disk before the job reads done;
        version = s->version;                                 // not_found if the session was deleted
    }
    std::lock_guard lock(job.mutex);
    job.state = JobState::Done;
    job.result = {{"version", version}, {"report", protocol::solveReportToJson(result.report)}};
}

void SessionService::solveLightsAndCommit(Job& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options,
                                          core::GpuDevice& device) {
    SolveInputs in = snapshot(*s);
    core::Lighting lighting = core::lightingForLightSolve(in.lighting, options.lights);
    auto report = [&](const core::SolveProgress& p, const char* block, int round) {
        nlohmann::json progress = protocol::solveProgressToJson(p);
        progress["block"] = block;
        if (round > 0) progress["round"] = round;
        {
            std::lock_guard lock(job.mutex);
            job.progress = progress;
        }
        job.emit(JobEvent::Progress, progress);
        m_gl->runShortTasks(device);  // renders waiting for the GL thread run between iterations
    };
    nlohmann::json result;
    std::optional<core::Volume> volume;
    if (options.lights.withVolume) {
        core::CombinedSolveResult r = core::solveLightsAndVolume(
            device, in.volume, lighting, in.views, options, options.lights.rounds,
            [&](const core::CombinedProgress& p) { report(p.inner, p.block, p.round); }, &job.cancel);
        lighting.environment.setRadiance(r.radiance);
        volume = std::move(r.volume);
        result["rounds"] = r.rounds;
        result["rms_history"] = r.rmsHistory;
        result["total_ms"] = r.totalMs;
    } else {
        core::LightSolver solver(device, in.volume, lighting, std::move(in.views), options, &job.cancel);
        const core::LightSolveResult r = solver.run([&](const core::SolveProgress& p) { report(p, "lights", 0); }, &job.cancel);
        lighting.environment.setRadiance(r.radiance);
        result["report"] = protocol::solveReportToJson(r.report);
        result["light_volumes"] = {{"ms", r.lightVolumeMs}, {"bytes", r.lightVolumeBytes}};
    }
    std::shared_ptr<core::GpuVolume> stale;  // freed here, on the GL thread
    {
        std::lock_guard lock(s->mutex);
        // Only the environment: the sun, lights, background or phase may have been set meanwhile.
        lighting.validate();  // never store what a breakdown left non-finite
        s->lighting.environment = lighting.environment;
        if (lighting.background.fromLobes)  // "lights": {"background": true}: the sky behind is solved too
            s->lighting.background.fromLobes = true, s->lighting.background.environment = nullptr;
        lighting = s->lighting;
        if (volume) stale = commitVersion(*s, std::move(*volume));  // saves the session, lighting included
        else saved(*s);
        result["version"] = s->version;
    }
    result["lighting"] = lightingJson(*s, lighting);
    result["environment_url"] = "/api/v1/sessions/" + s->id + "/lighting/environment.exr";
    std::lock_guard lock(job.mutex);
    job.state = JobState::Done;
    job.result = std::move(result);
}

void SessionService::runJob(Job& job, const std::function<void()>& work) {
    if (job.cancel) {
        job.fail(JobState::Cancelled, protocol::ErrorCode::Cancelled, "cancelled before it started");
        return;
    }
    job.setState(JobState::Running);
    saved(job);
    spdlog::info("job {} running", job.id);
    try {
        work();
    } catch (...) {
        const protocol::ErrorReport e = protocol::describeException(std::current_exception());
        job.fail(e.code == protocol::ErrorCode::Cancelled ? JobState::Cancelled : JobState::Failed, e.code, e.message, e.details);
    }
}

void SessionService::finishJob(Job& job) {
    JobState state;
    {
        std::lock_guard lock(job.mutex);
        state = job.state;
    }
    spdlog::info("job {} {}", job.id, protocol::jobStateName(state));
    try {
        saved(job);
    } catch (const std::exception& e) {
        spdlog::error("job {}: cannot record its end: {}", job.id, e.what());
    }
    job.emit(protocol::finalEvent(state), job.toJson());
}

}  // namespace volstyle::server

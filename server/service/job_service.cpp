// A solve job on the GL thread: snapshot the session, solve with progress and previews, commit
// the result as a new version, record the final state (JobService, SPEC §3 jobs).
#include <spdlog/spdlog.h>

#include <algorithm>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/solve/combined_solve.h"
#include "core/solve/light_solver.h"
#include "core/solve/solve_cache.h"
#include "core/solve/solver.h"
#include "protocol/error_body.h"
#include "server/service/services.h"

namespace volstyle::server {
namespace {

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
    SolveInputs in{s.volume.current, s.light.lighting, {}, {}};
    for (const auto& v : s.views.list) {
        if (v.frame) continue;  // a frame of the animation: POST …/animate solves it
        in.viewIds.push_back(v.id);
        in.views.push_back({v.id, v.camera, v.target.value_or(core::Image()), v.weights, v.background, v.clippedPixels});
    }
    return in;
}

}  // namespace

void JobService::runSolve(const std::shared_ptr<Job>& job, const std::shared_ptr<Session>& s,
                              const core::SolveOptions& options, core::GpuDevice& device) {
    {
        std::lock_guard lock(s->mutex);
        m_ctx.dropPreviews(*s);  // earlier jobs' last iterates: this job's previews replace them
    }
    m_ctx.runJob(*job, [&] { solveAndCommit(*job, s, options, device); });
    std::shared_ptr<core::GpuVolume> preview;  // freed here, on the GL thread, when the job is done
    {
        std::lock_guard lock(job->mutex);
        if (job->state == JobState::Done) preview = std::move(job->preview);
    }
    m_ctx.finishJob(*job);
}

void JobService::reportPhase(Job& job, core::SolvePhase phase) {
    core::SolveProgress p;
    p.phase = phase;
    {
        std::lock_guard lock(job.mutex);  // the iteration and its figures so far stay in the event
        if (const auto* last = std::get_if<protocol::SolveJobProgress>(&job.progress)) p = last->solve, p.phase = phase;
    }
    job.report(protocol::SolveJobProgress{p, {}, 0});
}

std::vector<std::shared_ptr<Job>> JobService::all() const {
    std::vector<std::shared_ptr<Job>> jobs = m_ctx.jobs.all();
    std::sort(jobs.begin(), jobs.end(), [](const auto& a, const auto& b) { return a->sequence < b->sequence; });
    return jobs;
}

void JobService::solveAndCommit(Job& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options,
                                    core::GpuDevice& device) {
    if (options.lights.solve) return solveLightsAndCommit(job, s, options, device);
    reportPhase(job, core::SolvePhase::PreparingViews);
    SolveInputs in = snapshot(*s);
    // Every view a stroke left alone keeps its rows of W and renders from the last solve.
    core::Solver solver(device, in.volume, in.lighting, std::move(in.views), options, m_ctx.solveCacheOnGl());
    auto lastPreview = Clock::now() - std::chrono::hours(1);
    core::SolveResult result = solver.run(
        [&](const core::SolveProgress& p) {
            job.report(protocol::SolveJobProgress{p, {}, 0});
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
                protocol::PreviewEvent event{p.iteration, {}};
                for (const auto& id : in.viewIds) event.urls.emplace_back(id, "/api/v1/jobs/" + job.id + "/preview/" + id + ".png");
                {
                    std::lock_guard lock(job.mutex);
                    job.preview = std::move(preview);
                }
                job.emit({JobEvent::Preview, std::move(event)});
            }
            m_ctx.gl->runShortTasks(device);  // renders waiting for the GL thread run between iterations
        },
        &job.cancel);
    reportPhase(job, core::SolvePhase::Writing);
    int version = 0;
    std::shared_ptr<core::GpuVolume> stale;  // freed here, on the GL thread
    {
        std::lock_guard lock(s->mutex);
        stale = m_ctx.commitVersion(*s, std::move(result.volume));  // on disk before the job reads done;
        version = s->volume.version;                                 // not_found if the session was deleted
    }
    std::lock_guard lock(job.mutex);
    job.state = JobState::Done;
    job.result = protocol::SolveJobResult{version, result.report};
}

void JobService::solveLightsAndCommit(Job& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options,
                                          core::GpuDevice& device) {
    SolveInputs in = snapshot(*s);
    core::Lighting lighting = core::lightingForLightSolve(in.lighting, options.lights);
    auto report = [&](const core::SolveProgress& p, const char* block, int round) {
        job.report(protocol::SolveJobProgress{p, block, round});
        m_ctx.gl->runShortTasks(device);  // renders waiting for the GL thread run between iterations
    };
    protocol::LightsJobResult result;
    std::optional<core::Volume> volume;
    if (options.lights.withVolume) {
        core::CombinedSolveResult r = core::solveLightsAndVolume(
            device, in.volume, lighting, in.views, options, options.lights.rounds,
            [&](const core::CombinedProgress& p) { report(p.inner, p.block, p.round); }, &job.cancel);
        lighting.environment.setRadiance(r.radiance);
        volume = std::move(r.volume);
        result.rounds = r.rounds;
        result.rmsHistory = r.rmsHistory;
        result.totalMs = r.totalMs;
    } else {
        core::LightSolver solver(device, in.volume, lighting, std::move(in.views), options, &job.cancel);
        const core::LightSolveResult r = solver.run([&](const core::SolveProgress& p) { report(p, "lights", 0); }, &job.cancel);
        lighting.environment.setRadiance(r.radiance);
        result.report = r.report;
        result.lightVolumeMs = r.lightVolumeMs;
        result.lightVolumeBytes = r.lightVolumeBytes;
    }
    std::shared_ptr<core::GpuVolume> stale;  // freed here, on the GL thread
    {
        std::lock_guard lock(s->mutex);
        // Only the environment: the sun, lights, background or phase may have been set meanwhile.
        lighting.validate();  // never store what a breakdown left non-finite
        s->light.lighting.environment = lighting.environment;
        if (lighting.background.fromLobes)  // "lights": {"background": true}: the sky behind is solved too
            s->light.lighting.background.fromLobes = true, s->light.lighting.background.environment = nullptr;
        lighting = s->light.lighting;
        if (volume) {
            stale = m_ctx.commitVersion(*s, std::move(*volume));  // saves the session, lighting included
        } else {
            m_ctx.shownChanged(*s);  // the environment lights the renders now (streams, work ahead)
            m_ctx.saved(*s);
        }
        result.version = s->volume.version;
        result.lighting = lighting;
        result.sessionMap = s->light.environmentMap;  // named "session" in the answer
    }
    result.environmentUrl = "/api/v1/sessions/" + s->id + "/lighting/environment.exr";
    std::lock_guard lock(job.mutex);
    job.state = JobState::Done;
    job.result = std::move(result);
}

std::filesystem::path JobService::jobFile(const std::string& jobId, const std::string& name) const {
    m_ctx.job(jobId);  // not_found for no such job
    const std::filesystem::path path = m_ctx.jobFilesDir(jobId) / name;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec) && m_ctx.persist) {
        std::lock_guard lock(m_ctx.storeLoads);  // another replica ran it: its files are in the store (read once)
        if (!std::filesystem::is_regular_file(path, ec)) m_ctx.persist->fetchJobFiles(jobId);
    }
    if (!std::filesystem::is_regular_file(path, ec))
        throw ApiError(ErrorCode::NotFound, "job '" + jobId + "' has no file '" + name + "' (yet)");
    return path;
}

std::shared_ptr<Job> JobService::startSolve(const std::shared_ptr<Session>& session, const core::SolveOptions& options,
                                            const JobOrigin& origin) {
    Session& s = *session;
    if (!origin.adopted) m_ctx.checkJobQueue(s);  // an adopted job is counted already
    {
        std::lock_guard lock(s.mutex);
        bool anyTarget = false;
        for (const auto& v : s.views.list) anyTarget |= v.target.has_value() && !v.frame;
        if (!anyTarget)
            throw ApiError(ErrorCode::InvalidArgument, "no view of the volume has a target (views of an animation's frames are solved by "
                                                       "POST …/animate); PUT …/views/{vid}/target first");
        // "views" names views of this session that have targets: check now, not when the job runs.
        std::vector<protocol::FieldError> problems;
        for (size_t i = 0; i < options.views.size(); ++i) {
            auto it = std::find_if(s.views.list.begin(), s.views.list.end(), [&](const SessionView& v) { return v.id == options.views[i]; });
            if (it == s.views.list.end()) problems.push_back({"/views/" + std::to_string(i), "no view '" + options.views[i] + "' in this session"});
            else if (!it->target) problems.push_back({"/views/" + std::to_string(i), "view '" + options.views[i] + "' has no target yet"});
            else if (it->frame)
                problems.push_back({"/views/" + std::to_string(i), "view '" + options.views[i] + "' shows frame " + std::to_string(*it->frame) +
                                                                       " of the animation: POST …/animate solves it"});
        }
        if (!problems.empty()) throw protocol::ValidationError(problems);
        if (!options.lights.solve) s.lastSolveOptions = options;  // what work ahead prepares the next solve for
    }
    auto job = m_ctx.queueJob(s, origin);
    m_ctx.gl->submit([this, job, session, options](core::GpuDevice& device) { runSolve(job, session, options, device); });
    return job;
}

void JobService::resume(const ClaimedJob& claimed) {
    std::shared_ptr<Job> job;
    try {
        job = m_ctx.adoptJob(claimed);
        if (claimed.cancel) throw ApiError(ErrorCode::Cancelled, "cancelled while its replica was down");
        if (claimed.attempt > kMaxAttempts)
            throw ApiError(ErrorCode::Interrupted, "its replica stopped while it ran " + std::to_string(kMaxAttempts) +
                                                       " times (a job that brings its replica down is not run again): start it again");
        const auto resumer = m_resumers.find(claimed.kind);
        if (resumer == m_resumers.end() || claimed.inputs.empty())
            throw ApiError(ErrorCode::Interrupted, "the replica running this job stopped, and a job of kind '" + claimed.kind +
                                                       "' is not run again elsewhere: start it again");
        auto session = m_ctx.find(claimed.session);  // as the store has it now (not_found: deleted)
        resumer->second(JobOrigin{claimed.kind, claimed.inputs, job}, session);
    } catch (...) {
        if (!job) throw;  // not adopted: its lease lapses again and it is claimed again
        const protocol::ErrorReport e = protocol::describeException(std::current_exception());
        if (e.code == ErrorCode::Cancelled) job->fail(JobState::Cancelled, e.code, e.message);
        else if (e.code == ErrorCode::Interrupted) job->fail(JobState::Failed, e.code, e.message);
        else job->fail(JobState::Failed, ErrorCode::Interrupted, "its replica stopped, and it could not run again here: " + e.message, e.details);
        m_ctx.finishJob(*job);
    }
}

}  // namespace volstyle::server

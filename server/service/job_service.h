#pragma once
/// \file job_service.h
/// Solve jobs (SPEC §2–3) and every job's lookup, files and cancel: a solve is checked when it
/// is asked for, recorded, and run on the GL thread, which commits its result as a new version.

#include <map>

#include "server/service/service_context.h"

namespace volstyle::server {

class JobService {
public:
    explicit JobService(ServiceContext& ctx) : m_ctx(ctx) {}

    /// Starts a job of one kind again from its recorded request (`origin.request`, read by the
    /// HTTP layer's parser) for session `s`, as the store has it now: the route's own start call
    /// with `origin` (adopted). Throws as that call does.
    using Resumer = std::function<void(const JobOrigin& origin, const std::shared_ptr<Session>& s)>;

    /// `origin`: the request's kind and body (the job queue keeps them), or a job run again.
    std::shared_ptr<Job> startSolve(const std::shared_ptr<Session>& s, const core::SolveOptions& options, const JobOrigin& origin = {});
    /// Runs a job claimed from the queue again, from its request, with its kind's resumer; one
    /// that cannot (no resumer, no request, the session gone, its request no longer valid) fails
    /// `interrupted` with why, for its client to start it again.
    void resume(const ClaimedJob& claimed);
    /// Registered by each route module for the kinds of job it starts (before the queue starts).
    void addResumer(const std::string& kind, Resumer r) { m_resumers[kind] = std::move(r); }
    std::shared_ptr<Job> job(const std::string& id) const { return m_ctx.job(id); }  ///< ApiError not_found
    /// Every job the server holds (finished ones until pruned), oldest first.
    std::vector<std::shared_ptr<Job>> all() const;
    /// A progress event naming the phase a solve begins (its last iteration's figures kept).
    static void reportPhase(Job& job, core::SolvePhase phase);
    /// The path of a file job `jobId` wrote (frame_00000.png, video.mp4); not_found without it.
    std::filesystem::path jobFile(const std::string& jobId, const std::string& name) const;
    void cancel(Job& job) { m_ctx.cancelJob(job); }
    /// A job another replica runs, read again from the queue (nothing for this replica's own).
    void refresh(Job& job) { m_ctx.refreshRemote(job); }

private:
    // The solve job on the GL thread (solve_job.cpp).
    void runSolve(const std::shared_ptr<Job>& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options,
                  core::GpuDevice& device);
    void solveAndCommit(Job& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options, core::GpuDevice& device);
    /// "unknowns": ["lights", …]: the environment lobes (and the volume's unknowns in turn); the
    /// session's lighting gets the solved radiances (and the volume a new version).
    void solveLightsAndCommit(Job& job, const std::shared_ptr<Session>& s, const core::SolveOptions& options, core::GpuDevice& device);

    /// Runs of one job (its first and re-runs) after which a replica dying under it ends it.
    static constexpr int kMaxAttempts = 3;

    ServiceContext& m_ctx;
    std::map<std::string, Resumer> m_resumers;
};

}  // namespace volstyle::server

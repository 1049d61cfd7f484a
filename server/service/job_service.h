#pragma once
/// \file job_service.h
/// Solve jobs (SPEC §2–3) and every job's lookup, files and cancel: a solve is checked when it
/// is asked for, recorded, and run on the GL thread, which commits its result as a new version.

#include "server/service/service_context.h"

namespace volstyle::server {

class JobService {
public:
    explicit JobService(ServiceContext& ctx) : m_ctx(ctx) {}

    /// Reads a solve's recorded request (its body as sent) into its options for session `s`: the
    /// HTTP layer's parser, so a replica can run again a solve another one started.
    using SolveDecoder = std::function<core::SolveOptions(const std::string& request, Session& s)>;

    /// `request`: the body as sent, kept in the job queue's row (with a PostgreSQL store) for a
    /// replica to run the solve again if this one dies.
    std::shared_ptr<Job> startSolve(const std::shared_ptr<Session>& s, const core::SolveOptions& options, const std::string& request = "");
    /// Runs a job claimed from the queue: a solve again from its request and the session as the
    /// store has it now; a job of another kind (or a solve without its request) fails
    /// `interrupted`, for its client to start again.
    void resume(const ClaimedJob& claimed);
    void setSolveDecoder(SolveDecoder decode) { m_decodeSolve = std::move(decode); }
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

    ServiceContext& m_ctx;
    SolveDecoder m_decodeSolve;
};

}  // namespace volstyle::server

#pragma once
/// \file service_context.h
/// What the session services share (issue #36): the limits, the memory budget, the session and
/// job tables, the store, the GL executor and the engines that live on its thread, and the steps
/// every service takes — write a change before answering (`saved`), make a volume the newest
/// version, queue and run a job, find a session's GPU copy. Each service (sessions, volumes and
/// frames, stylizer, jobs) is a small class on one context.
///
/// Rules: every change is on disk (the store) before a method returns; GL work runs on the
/// GlExecutor; a session's lock is never held while waiting for the GL thread (a finishing solve
/// needs it).

#include <atomic>
#include <map>

#include "core/solve/solve_cache.h"
#include "server/service/service_types.h"

namespace volstyle::server {

struct ServiceContext {
    /// Restores sessions and jobs from `dataDir` (empty: in memory only). GL work goes to `gl`;
    /// none given: its own GL thread (GlWorker).
    ServiceContext(ServiceLimits limits, const std::string& dataDir, std::unique_ptr<GlExecutor> gl);
    ~ServiceContext();  ///< shutdown(), then the job scratch folder goes
    /// Cancels the jobs, frees GPU objects on the GL thread, then stops it once the work queued
    /// for it is drained (that work calls into the services). Idempotent.
    void shutdown();
    /// With the job queue: the unfinished jobs' leases handed back for another replica to run.
    void handBackJobs();
    ServiceContext(const ServiceContext&) = delete;
    ServiceContext& operator=(const ServiceContext&) = delete;

    // Lookups.
    std::shared_ptr<Session> find(const std::string& id);  ///< ApiError not_found
    /// With a PostgreSQL store: `held` (may be null), or the session as the store has it when
    /// another replica made or changed it (nullptr: the store has none).
    std::shared_ptr<Session> freshFromStore(const std::string& id, std::shared_ptr<Session> held);
    /// ApiError not_found. With the job queue, a job another replica runs is read from the queue
    /// (a remote copy here, refreshed at each lookup).
    std::shared_ptr<Job> job(const std::string& id);
    SessionView view(Session& s, const std::string& viewId) const;  ///< a copy; ApiError not_found
    core::Lighting lighting(Session& s) const;

    // Writing what changed.
    /// Throws not_found if `s` was deleted; else writes it and recounts its memory (its lock held).
    void saved(Session& s);
    /// Writes a job's record (a remote copy's is not this replica's to write); with the queue, a
    /// job another replica took over is cancelled here instead.
    void saved(Job& j);
    /// Forgets the oldest finished jobs beyond ServiceLimits::finishedJobsKept: memory, record
    /// on disk, the id in its session's list, and its preview copy (freed on the GL thread).
    void pruneJobs();
    void checkUploadSize(const std::string& bytes, const std::string& what) const;

    // Volume versions.
    /// Makes `volume` the newest version, on disk before it returns. Call with the session's
    /// lock held; returns the stale GPU copy (release() it after unlocking).
    /// `shows`: the version whose content `volume` is (a revert); 0: new content.
    std::shared_ptr<core::GpuVolume> commitVersion(Session& s, core::Volume volume, int shows = 0);
    /// commitVersion() for an undo or redo: the new version shows `shows`, and the stacks are the
    /// caller's (an edit's bookkeeping is skipped).
    std::shared_ptr<core::GpuVolume> commitStep(Session& s, core::Volume volume, int shows);
    void release(std::shared_ptr<core::GpuVolume> gpu);
    /// A held copy of a session that the store replaced or deleted (another replica's doing):
    /// marked removed, its memory uncharged, its jobs cancelled, its GPU copy freed on the GL thread.
    void retire(Session& s);
    /// What a render of `s` shows changed (a version, the lighting, the environment map): moves
    /// its shownRevision and wakes its streams (the lock held).
    void shownChanged(Session& s);
    /// Writes the stylizer's scene, moves its revision and wakes its streams (the lock held).
    /// `history`: the undo/redo stacks changed too (written apart from the scene).
    void stylizerChanged(Session& s, bool history = false);

    // Jobs.
    /// A new job of session `s` (too_many_jobs at its queue limit), recorded and listed. With the
    /// job queue, its row holds `kind` and `inputs` (what another replica runs it again from;
    /// empty: it cannot be run again) under this replica's lease.
    /// An adopted origin's job is returned as it is (checked when it was first asked for).
    std::shared_ptr<Job> queueJob(Session& s, const JobOrigin& origin = {});
    /// A job claimed from the queue, local here now and queued again (its row written).
    std::shared_ptr<Job> adoptJob(const ClaimedJob& c);
    /// Cancels a job: here, or (a remote copy) by asking the replica running it through the queue.
    void cancelJob(Job& j);
    /// The queue's notifications (JobQueue::Listener): events and states of remote copies, cancels.
    void onQueueNotice(const std::string& id, const std::string& what, const std::string& data);
    /// After a renewal: cancels each of `running` (local jobs that were running before it) whose
    /// lease another replica holds now, and each whose cancel was asked elsewhere.
    void checkLeases(const std::vector<std::shared_ptr<Job>>& running, const std::vector<HeldLease>& held);
    /// This replica no longer holds the job's lease: its copy becomes remote and is cancelled.
    void loseJob(Job& j, const std::string& why);
    void checkJobQueue(const Session& s) const;  ///< too_many_jobs at the session's queue limit
    /// Runs `work` as the job's body: cancelled before it starts, or running (recorded) until it
    /// returns (it sets the result and done) or throws (failed or cancelled, with the error).
    void runJob(Job& job, const std::function<void()>& work);
    void finishJob(Job& job);
    /// Where a job's files go: its folder in the data directory, or in `scratch`.
    std::filesystem::path jobFilesDir(const std::string& jobId) const;
    /// On the GL thread: frees the preview copies of the session's finished jobs.
    void dropPreviews(const Session& s);

    // Work ahead (solve_prefetch.cpp).
    /// Queues, for when the GL thread is idle, the renders the session's next solve needs first
    /// (each view's, core/solve/solve_prefetch.h) under its last solve's options (the defaults
    /// before one). Called by saved(): whatever changed, the views, volume or lighting may have.
    void prefetchSolve(const Session& s);
    /// The idle task: false when it yielded to a request (it runs again at the next idle moment).
    bool runPrefetch(const std::string& sessionId, core::GpuDevice& device, const std::atomic<bool>& yield);
    /// On the GL thread: the solve cache, created on first use (limits.solveCacheBytes > 0).
    core::SolveCache* solveCacheOnGl();

    // The GL thread's engines (created on first use, GL thread only).
    core::Renderer& renderer(core::GpuDevice& device);
    core::Stylizer& stylizerEngine(core::GpuDevice& device);
    /// On the GL thread, with the session's lock held: the session's GPU copy, uploaded if there
    /// is none (not_found once removed). Shared, so a render can drop the lock and keep it alive.
    std::shared_ptr<core::GpuVolume> sessionGpu(Session& s);
    /// On the GL thread: sessionGpu() under the session's lock, released before any GL work.
    std::shared_ptr<core::GpuVolume> lockedSessionGpu(Session& s);
    /// On the GL thread: frees every session's GPU copy, every job's preview and the engines.
    void freeGpuObjects();
    /// A remote copy of job `id` (`held`, refreshed, or a new one); nullptr when the queue has none.
    std::shared_ptr<Job> remoteJob(const std::string& id, std::shared_ptr<Job> held);
    void refreshRemote(Job& j, const std::string& record);
    /// A remote copy read again from the queue (a notification may be lost while the listener
    /// reconnects: a stream of a remote job refreshes it while quiet). Nothing for a local job.
    void refreshRemote(Job& j);
    /// Sends the job's events to other replicas through the queue.
    void relayEvents(Job& j);

    /// A slot of decodeSlots, held while an upload's pixels are decoded.
    struct DecodeSlot {
        explicit DecodeSlot(std::counting_semaphore<>& s) : slots(s) { slots.acquire(); }
        ~DecodeSlot() { slots.release(); }
        std::counting_semaphore<>& slots;
    };
    static constexpr int kConcurrentDecodes = 2;
    /// Undo steps a session keeps (each names a version; the versions themselves stay).
    static constexpr size_t kMaxUndoSteps = 256;

    ServiceLimits limits;
    MemoryBudget memory{limits.memory};
    SessionStore sessions;
    JobStore jobs;
    std::mutex jobRecords;  ///< orders writing a job's record against forgetting it
    std::unique_ptr<Persistence> persist;  ///< null: in memory only
    std::unique_ptr<JobQueue> queue;       ///< with a PostgreSQL store only
    std::mutex storeLoads;                 ///< one session read from the store at a time
    std::mutex remoteCopies;               ///< one remote copy of a job made at a time
    std::filesystem::path scratch;          ///< job files without a data directory (removed at exit)
    std::counting_semaphore<> decodeSlots{kConcurrentDecodes};
    std::unique_ptr<core::Renderer> rendererEngine;             ///< GL thread only
    std::unique_ptr<core::Stylizer> stylizer;                   ///< GL thread only
    std::unique_ptr<core::TranslucentRenderer> translucent;     ///< GL thread only; created on first use
    std::unique_ptr<core::SolveCache> solveCache;               ///< GL thread only; created by the first solve
    /// Work ahead of one session (GL thread only): the signature of what it last finished (the
    /// same again: nothing to do), and while one is unfinished, its signature and its volume's key
    /// (kept while it yields to requests: hashing a 128³ volume's grids takes ~0.1 s).
    struct PrefetchState {
        std::string done, pending;
        core::VolumeKey key;
    };
    std::map<std::string, PrefetchState> prefetched;
    std::atomic<uint64_t> prefetchedViews{0};  ///< views rendered ahead of solves (GET /metrics)
    std::atomic<uint64_t> prefetchedRows{0};   ///< views whose rows were written ahead of solves
    std::atomic<bool> workAheadStopped{false};  ///< set by shutdown(): idle tasks do nothing more
    std::unique_ptr<GlExecutor> gl;  ///< last: destroyed first, so its thread stops before the engines go
};

}  // namespace volstyle::server

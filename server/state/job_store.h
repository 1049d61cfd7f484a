#pragma once
/// \file job_store.h
/// Solve jobs: their state, progress and result, and the events the SSE stream replays
/// (`progress`, `preview`, then one final event named after the final state).

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/render/gpu_volume.h"
#include "protocol/error_code.h"
#include "protocol/job_values.h"
#include "protocol/vocabulary.h"

namespace volstyle::server {

struct Job {
    std::string id, session;
    uint64_t sequence = 0;  ///< creation order (restored jobs: the order of their files' times)
    std::atomic<bool> cancel{false};
    /// Pruned from the store: its record must not be written again (ServiceContext::saved).
    bool forgotten = false;
    /// Sends each non-final event on to other replicas (the job queue's NOTIFY), once emitted.
    using Relay = std::function<void(const protocol::JobEventData&)>;

    mutable std::mutex mutex;
    std::condition_variable changed;
    protocol::JobState state = protocol::JobState::Queued;
    protocol::JobProgress progress;
    protocol::JobResult result;
    std::optional<protocol::JobError> error;
    std::vector<protocol::JobEventData> events;
    /// Another replica runs it (job queue): its state is read from the queue's record, its events
    /// come through notifications; nothing here runs it or writes its record.
    bool remote = false;
    Relay relay;
    /// The latest iterate on the GPU, for previews: created and updated on the GL thread while the
    /// job runs (one copy per job, not one upload per request). A done job frees it (previews
    /// then show the session's version, the solution); a failed or cancelled one keeps it until
    /// the session's next solve starts or the session is deleted.
    std::shared_ptr<core::GpuVolume> preview;

    bool isFinished() const { return protocol::isFinished(state); }  ///< the mutex held
    bool isFinishedLocked() const {
        std::lock_guard lock(mutex);
        return isFinished();
    }
    void setState(protocol::JobState s);
    /// Ends the job in state `s` (failed or cancelled) with an error body of `code` and `message`.
    void fail(protocol::JobState s, protocol::ErrorCode code, const std::string& message,
              const std::vector<protocol::FieldError>& details = {});
    /// Sets the progress and sends it as a progress event.
    void report(protocol::JobProgress p);
    void emit(protocol::JobEventData event);  ///< appends, wakes listeners, relays it
    void setRelay(Relay r);
    /// Sends the final event, the job's snapshot now (after its state became final).
    void emitFinal();
    protocol::JobInfo info() const;
};

class JobStore {
public:
    std::shared_ptr<Job> add(const std::string& session);
    std::shared_ptr<Job> find(const std::string& id) const;
    void restore(std::shared_ptr<Job> job);
    /// Adds `job` unless one with its id is held; the one held then.
    std::shared_ptr<Job> insertIfAbsent(std::shared_ptr<Job> job);
    void remove(const std::string& id);
    /// Job `id` to be run here (claimed from the queue): the copy held (a remote one, which
    /// streams keep watching) made local and queued again, or a new one.
    std::shared_ptr<Job> adopt(const std::string& id, const std::string& session);
    /// Jobs of a session not yet finished (the queue limit counts them).
    size_t pending(const std::string& session) const;
    std::vector<std::shared_ptr<Job>> all() const;
    /// Removes the oldest finished jobs beyond `keep` and returns them (their records are the
    /// caller's to delete). Unfinished jobs are never pruned. Without this, every job a server ever
    /// ran stayed in memory and on disk (the soak grew 16% in 10 minutes).
    std::vector<std::shared_ptr<Job>> prune(size_t keep);

private:
    mutable std::mutex m_mutex;
    uint64_t m_sequence = 0;
    std::map<std::string, std::shared_ptr<Job>> m_jobs;
};

}  // namespace volstyle::server

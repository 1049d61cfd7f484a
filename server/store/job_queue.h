#pragma once
/// \file job_queue.h
/// The job queue on PostgreSQL (issue #41 item 2): a row per job (volstyle_jobs) with its kind,
/// its inputs (the request that started it, as it came), its record (job_record.h) and a lease.
/// The replica running a job renews its lease; when a replica dies its leases lapse and another
/// replica claims the job (`FOR UPDATE SKIP LOCKED`: two replicas never claim one job) and runs
/// it again from its inputs. Progress goes through `LISTEN/NOTIFY`, so an event stream on any
/// replica sees a job another replica runs. The data folder alone has no queue: its jobs are its
/// server's.

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace volstyle::server {

/// A job this replica has just claimed from a replica whose lease lapsed.
struct ClaimedJob {
    std::string id, session, kind, inputs;
    std::string previousOwner;
    int attempt = 1;  ///< 2 for the first re-run
    bool cancel = false;  ///< DELETE /jobs/{jid} was asked while no replica ran it
};

/// A lease this replica renewed: the job is still its own; `cancel`: DELETE /jobs/{jid} was
/// asked of another replica.
struct HeldLease {
    std::string id;
    bool cancel = false;
};

class JobQueue {
public:
    /// Called by listen() for each notification: a job's id and what happened ("state": its
    /// record changed, read it again; "cancel"; else an event's name, with its data as JSON).
    using Listener = std::function<void(const std::string& job, const std::string& what, const std::string& data)>;

    virtual ~JobQueue() = default;
    /// This process's owner token ("<replica>/<8 hex>": a restarted replica never renews a
    /// lease its previous life held).
    virtual const std::string& owner() const = 0;
    /// Records a new job, leased to this replica.
    virtual void add(const std::string& id, const std::string& session, const std::string& kind, const std::string& inputs,
                     const std::string& state, const std::string& record) = 0;
    /// Writes a job's record and state and tells every replica ("state"). False when this
    /// replica no longer holds the job (another claimed it): nothing is written.
    virtual bool write(const std::string& id, const std::string& state, const std::string& record) = 0;
    /// Tells every replica of an event of a job this replica runs (not kept: the record is). Queued
    /// and sent on a thread of the queue's own; write() sends what was queued before it.
    virtual void publish(const std::string& id, const std::string& event, const std::string& data) = 0;
    /// A job's stored record (nullopt: none).
    virtual std::optional<std::string> record(const std::string& id) = 0;
    /// Asks the replica running a job to cancel it; false when there is no such job.
    virtual bool requestCancel(const std::string& id) = 0;
    /// Removes a job's row, if this replica holds it or it is finished.
    virtual void remove(const std::string& id) = 0;
    /// Hands back the leases of `ids` (this replica stops): another replica claims them at once.
    virtual void release(const std::vector<std::string>& ids) = 0;
    /// Renews the leases of `ids`, the unfinished jobs this replica holds in memory; those it still
    /// holds. A row leased to this replica but not named (a claim whose start failed) lapses.
    virtual std::vector<HeldLease> renew(const std::vector<std::string>& ids) = 0;
    /// Claims the oldest unfinished job whose lease lapsed (none: nullopt).
    virtual std::optional<ClaimedJob> claimLapsed() = 0;
    /// Waits up to `timeout` for notifications (on its own connection) and hands each to `on`.
    virtual void listen(const Listener& on, std::chrono::milliseconds timeout) = 0;
    virtual std::chrono::milliseconds lease() const = 0;
    /// The jobs in the queue by state, all replicas' (GET /metrics).
    virtual std::vector<std::pair<std::string, long long>> countByState() = 0;
};

/// The PostgreSQL queue (pg_job_queue.cpp) at `url` (its schema already migrated by the file
/// mirror); `replica` names this replica in the owner token and in logs. IoError.
std::unique_ptr<JobQueue> openPostgresJobQueue(const std::string& url, const std::string& replica, std::chrono::milliseconds lease);

}  // namespace volstyle::server

#pragma once
/// \file job_queue_runner.h
/// A replica's part in the job queue (issue #41 item 2, store/job_queue.h), on two threads:
///   - leases: every third of a lease, renews the leases of the jobs running here (cancelling
///     any another replica holds now, or whose cancel was asked elsewhere), then claims the jobs
///     whose replicas' leases lapsed and hands each to `resume`;
///   - notifications: LISTENs for other replicas' job events and states (ServiceContext::onQueueNotice).

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

#include "server/service/service_context.h"

namespace volstyle::server {

class JobQueueRunner {
public:
    JobQueueRunner(ServiceContext& ctx, std::function<void(const ClaimedJob&)> resume);
    ~JobQueueRunner();  ///< stops both threads
    JobQueueRunner(const JobQueueRunner&) = delete;
    JobQueueRunner& operator=(const JobQueueRunner&) = delete;

private:
    void leases();
    /// Renews this replica's leases (cancelling the jobs it lost); `renewed` becomes now.
    void renew(std::chrono::steady_clock::time_point& renewed);
    void notifications();
    /// Sleeps up to `d`; false once stopping.
    bool pause(std::chrono::milliseconds d);

    ServiceContext& m_ctx;
    std::function<void(const ClaimedJob&)> m_resume;
    std::mutex m_mutex;
    std::condition_variable m_wake;
    bool m_stopping = false;
    std::thread m_leases, m_notifications;
};

}  // namespace volstyle::server

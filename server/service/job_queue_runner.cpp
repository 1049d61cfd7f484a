#include "server/service/job_queue_runner.h"

#include <spdlog/spdlog.h>

namespace volstyle::server {

JobQueueRunner::JobQueueRunner(ServiceContext& ctx, std::function<void(const ClaimedJob&)> resume)
    : m_ctx(ctx), m_resume(std::move(resume)), m_leases([this] { leases(); }), m_notifications([this] { notifications(); }) {}

JobQueueRunner::~JobQueueRunner() {
    {
        std::lock_guard lock(m_mutex);
        m_stopping = true;
    }
    m_wake.notify_all();
    m_leases.join();
    m_notifications.join();  // within one listen() timeout
}

bool JobQueueRunner::pause(std::chrono::milliseconds d) {
    std::unique_lock lock(m_mutex);
    return !m_wake.wait_for(lock, d, [&] { return m_stopping; });
}

void JobQueueRunner::leases() {
    JobQueue& queue = *m_ctx.queue;
    // Renewed three times a lease: one late renewal (a busy store) does not lose a job.
    const auto period = std::max(std::chrono::milliseconds(100), queue.lease() / 3);
    auto renewed = std::chrono::steady_clock::now();
    do {
        try {
            renew(renewed);
            // One claim at a time, renewing between them: starting a claimed job reads its
            // session from the store, and this replica's own leases must not lapse meanwhile.
            while (auto claimed = queue.claimLapsed()) {
                m_resume(*claimed);
                renew(renewed);
            }
        } catch (const std::exception& e) {
            spdlog::warn("job queue: {}", e.what());
        }
        if (std::chrono::steady_clock::now() - renewed > queue.lease()) {
            // No renewal for a whole lease (this replica cut off from the store): another replica
            // may run these jobs now, so this one stops them rather than commit twice.
            for (auto& j : m_ctx.jobs.all())
                if (!j->isFinishedLocked()) m_ctx.loseJob(*j, "its lease could not be renewed for a whole lease");
        }
    } while (pause(period));
}

void JobQueueRunner::renew(std::chrono::steady_clock::time_point& renewed) {
    // The jobs held here before the renewal; only those running are checked for a lost lease
    // (one queued since may not be in the store yet, and must not look lost).
    std::vector<std::shared_ptr<Job>> running;
    std::vector<std::string> held;
    for (auto& j : m_ctx.jobs.all()) {
        std::lock_guard lock(j->mutex);
        if (j->remote || j->isFinished()) continue;
        held.push_back(j->id);
        if (j->state == protocol::JobState::Running) running.push_back(j);
    }
    m_ctx.checkLeases(running, m_ctx.queue->renew(held));
    renewed = std::chrono::steady_clock::now();
}

void JobQueueRunner::notifications() {
    const JobQueue::Listener on = [this](const std::string& id, const std::string& what, const std::string& data) {
        try {
            m_ctx.onQueueNotice(id, what, data);
        } catch (const std::exception& e) {
            spdlog::debug("job queue: notice for job {} ({}): {}", id, what, e.what());
        }
    };
    while (pause(std::chrono::milliseconds(0))) m_ctx.queue->listen(on, std::chrono::milliseconds(250));
}

}  // namespace volstyle::server

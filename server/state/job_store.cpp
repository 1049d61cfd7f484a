#include "server/state/job_store.h"

#include <algorithm>

#include "server/state/session_store.h"

namespace volstyle::server {

void Job::setState(protocol::JobState s) {
    std::lock_guard lock(mutex);
    state = s;
}

void Job::fail(protocol::JobState s, protocol::ErrorCode code, const std::string& message,
               const std::vector<protocol::FieldError>& details) {
    std::lock_guard lock(mutex);
    state = s;
    error = protocol::JobError{code, message, details};
}

void Job::report(protocol::JobProgress p) {
    {
        std::lock_guard lock(mutex);
        progress = p;
    }
    emit({protocol::JobEvent::Progress, std::move(p)});
}

void Job::emit(protocol::JobEventData event) {
    Relay send;
    {
        std::lock_guard lock(mutex);
        if (!protocol::isFinal(event.event)) send = relay;  // the final state goes with the record
        events.push_back(event);
    }
    changed.notify_all();
    if (send) send(event);
}

void Job::setRelay(Relay r) {
    std::lock_guard lock(mutex);
    relay = std::move(r);
}

void Job::emitFinal() {
    protocol::JobInfo snapshot = info();
    emit({protocol::finalEvent(snapshot.state), std::move(snapshot)});
}

protocol::JobInfo Job::info() const {
    std::lock_guard lock(mutex);
    return {id, session, state, progress, result, error};
}

std::shared_ptr<Job> JobStore::add(const std::string& session) {
    auto job = std::make_shared<Job>();
    // The session's first 8 hex digits lead the job's id: a load balancer that hashes them sends
    // a job's requests to the replica that holds its session (docs/DEPLOY.md).
    job->id = SessionStore::newId();
    if (session.size() >= 8) job->id.replace(0, 8, session, 0, 8);
    job->session = session;
    std::lock_guard lock(m_mutex);
    job->sequence = ++m_sequence;
    m_jobs[job->id] = job;
    return job;
}

std::shared_ptr<Job> JobStore::adopt(const std::string& id, const std::string& session) {
    std::lock_guard lock(m_mutex);
    std::shared_ptr<Job>& slot = m_jobs[id];
    if (!slot) {
        slot = std::make_shared<Job>();
        slot->id = id;
        slot->session = session;
        slot->sequence = ++m_sequence;
    }
    std::lock_guard jl(slot->mutex);
    slot->remote = false;
    slot->state = protocol::JobState::Queued;
    slot->error.reset();
    slot->result = {};
    slot->progress = {};
    // A stream opened from now on must not replay an end this copy once saw and close.
    if (!slot->events.empty() && protocol::isFinal(slot->events.back().event)) slot->events.clear();
    return slot;
}

std::shared_ptr<Job> JobStore::insertIfAbsent(std::shared_ptr<Job> job) {
    std::lock_guard lock(m_mutex);
    std::shared_ptr<Job>& slot = m_jobs[job->id];
    if (!slot) {
        job->sequence = ++m_sequence;
        slot = std::move(job);
    }
    return slot;
}

void JobStore::remove(const std::string& id) {
    std::lock_guard lock(m_mutex);
    m_jobs.erase(id);
}

void JobStore::restore(std::shared_ptr<Job> job) {
    std::lock_guard lock(m_mutex);
    job->sequence = ++m_sequence;
    m_jobs[job->id] = std::move(job);
}

std::vector<std::shared_ptr<Job>> JobStore::prune(size_t keep) {
    std::lock_guard lock(m_mutex);
    std::vector<std::shared_ptr<Job>> finished;
    for (const auto& [id, j] : m_jobs) {
        std::lock_guard jl(j->mutex);
        if (j->isFinished()) finished.push_back(j);
    }
    if (finished.size() <= keep) return {};
    std::sort(finished.begin(), finished.end(), [](const auto& a, const auto& b) { return a->sequence < b->sequence; });
    finished.resize(finished.size() - keep);
    for (const auto& j : finished) m_jobs.erase(j->id);
    return finished;
}

std::shared_ptr<Job> JobStore::find(const std::string& id) const {
    std::lock_guard lock(m_mutex);
    auto it = m_jobs.find(id);
    return it == m_jobs.end() ? nullptr : it->second;
}

size_t JobStore::pending(const std::string& session) const {
    std::lock_guard lock(m_mutex);
    size_t n = 0;
    for (const auto& [id, j] : m_jobs) {
        std::lock_guard jl(j->mutex);
        n += j->session == session && !j->isFinished() && !j->remote ? 1 : 0;
    }
    return n;
}

std::vector<std::shared_ptr<Job>> JobStore::all() const {
    std::lock_guard lock(m_mutex);
    std::vector<std::shared_ptr<Job>> out;
    for (const auto& [id, j] : m_jobs) out.push_back(j);
    return out;
}

}  // namespace volstyle::server

#include "server/job_store.h"

#include "server/session_store.h"

namespace volstyle::server {

void Job::emit(const std::string& event, nlohmann::json data) {
    {
        std::lock_guard lock(mutex);
        events.emplace_back(event, std::move(data));
    }
    changed.notify_all();
}

nlohmann::json Job::toJson() const {
    std::lock_guard lock(mutex);
    return {{"id", id}, {"session", session}, {"state", state}, {"progress", progress}, {"result", result}, {"error", error}};
}

std::shared_ptr<Job> JobStore::add(const std::string& session) {
    auto job = std::make_shared<Job>();
    job->id = SessionStore::newId();
    job->session = session;
    std::lock_guard lock(m_mutex);
    m_jobs[job->id] = job;
    return job;
}

void JobStore::restore(std::shared_ptr<Job> job) {
    std::lock_guard lock(m_mutex);
    m_jobs[job->id] = std::move(job);
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
        n += j->session == session && !j->isFinished() ? 1 : 0;
    }
    return n;
}

}  // namespace volstyle::server

#pragma once
/// \file job_store.h
/// Solve jobs: their state, progress and result, and the events the SSE stream replays
/// (`progress`, `preview`, then one of `done`, `failed`, `cancelled`).

#include <nlohmann/json.hpp>

#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/volume/volume.h"

namespace volstyle::server {

struct Job {
    std::string id, session;
    std::atomic<bool> cancel{false};

    mutable std::mutex mutex;
    std::condition_variable changed;
    std::string state = "queued";  ///< queued, running, done, failed, cancelled
    nlohmann::json progress = nlohmann::json::object();
    nlohmann::json result = nullptr, error = nullptr;
    std::vector<std::pair<std::string, nlohmann::json>> events;  ///< (event name, data)
    std::optional<core::Volume> preview;                         ///< the latest iterate, for previews

    bool isFinished() const { return state == "done" || state == "failed" || state == "cancelled"; }
    void emit(const std::string& event, nlohmann::json data);   ///< appends and wakes listeners
    nlohmann::json toJson() const;
};

class JobStore {
public:
    std::shared_ptr<Job> add(const std::string& session);
    std::shared_ptr<Job> find(const std::string& id) const;
    void restore(std::shared_ptr<Job> job);
    /// Jobs of a session not yet finished (the queue limit counts them).
    size_t pending(const std::string& session) const;

private:
    mutable std::mutex m_mutex;
    std::map<std::string, std::shared_ptr<Job>> m_jobs;
};

}  // namespace volstyle::server

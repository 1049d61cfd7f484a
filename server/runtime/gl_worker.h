#pragma once
/// \file gl_worker.h
/// The server's GL thread (SPEC §3 Concurrency), the GlExecutor of `volstyle serve`: HTTP
/// threads post closures to it and wait for their results.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "server/runtime/gl_executor.h"

namespace volstyle::server {

/// The GL thread: it owns the GpuDevice (and so the GL context).
class GlWorker final : public GlExecutor {
public:
    /// Starts the thread and creates the context on it; throws GpuError if that fails.
    GlWorker();
    ~GlWorker() override;  ///< finishes queued work, then stops

    void runShortTasks(core::GpuDevice& device) override;
    const core::gl::Capabilities& capabilities() const override { return m_caps; }
    GlQueueDepth queueDepth() const override;
    core::gl::GpuMemory gpuMemory() const override { return {m_gpuTotal.load(), m_gpuAvailable.load()}; }

private:
    void post(std::function<void(core::GpuDevice&)> task, bool isLong) override;
    void postIdle(const std::string& key, IdleTask task) override;
    void loop(std::promise<void>& started);
    /// With the lock held and both queues empty: waits for a quiet moment, then runs the first idle
    /// task (unlocked), queuing it again if it yielded. False when there was none to run.
    bool runIdleTask(std::unique_lock<std::mutex>& lock, core::GpuDevice& device);
    /// Reads the driver's memory figures if a second has passed since the last read (GL thread).
    void sampleGpuMemory(std::chrono::steady_clock::time_point& last);

    std::thread m_thread;
    mutable std::mutex m_mutex;
    std::condition_variable m_wake;
    std::deque<std::function<void(core::GpuDevice&)>> m_short, m_long;
    std::deque<std::pair<std::string, IdleTask>> m_idle;
    std::atomic<bool> m_yield{false};  ///< raised when a task is queued while an idle one runs
    bool m_stopping = false;
    core::gl::Capabilities m_caps;
    std::atomic<long long> m_gpuTotal{-1}, m_gpuAvailable{-1};
};

}  // namespace volstyle::server

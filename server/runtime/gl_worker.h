#pragma once
/// \file gl_worker.h
/// The server's GL thread (SPEC §3 Concurrency), the GlExecutor of `volstyle serve`: HTTP
/// threads post closures to it and wait for their results.

#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

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

private:
    void post(std::function<void(core::GpuDevice&)> task, bool isLong) override;
    void loop(std::promise<void>& started);

    std::thread m_thread;
    mutable std::mutex m_mutex;
    std::condition_variable m_wake;
    std::deque<std::function<void(core::GpuDevice&)>> m_short, m_long;
    bool m_stopping = false;
    core::gl::Capabilities m_caps;
};

}  // namespace volstyle::server

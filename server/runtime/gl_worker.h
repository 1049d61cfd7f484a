#pragma once
/// \file gl_worker.h
/// The server's GL thread (SPEC §3 Concurrency): it owns the GpuDevice (and so the GL context);
/// HTTP threads post closures to it and wait for their results. Exceptions travel back to the
/// caller.

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>

#include "core/gl/context.h"
#include "core/gpu/gpu_device.h"

namespace volstyle::server {

class GlWorker {
public:
    /// Starts the thread and creates the context on it; throws GpuError if that fails.
    GlWorker();
    ~GlWorker();  ///< finishes queued work, then stops

    /// Runs a short `task(device)` (a render, a release) on the GL thread and returns its
    /// result (or rethrows its exception). Short tasks also run between a long task's iterations.
    template <typename F>
    auto run(F&& task) -> decltype(task(std::declval<core::GpuDevice&>())) {
        using R = decltype(task(std::declval<core::GpuDevice&>()));
        auto job = std::make_shared<std::packaged_task<R(core::GpuDevice&)>>(std::forward<F>(task));
        auto result = job->get_future();
        post([job](core::GpuDevice& r) { (*job)(r); }, /*isLong=*/false);
        return result.get();
    }

    /// Queues a long task (a solve) and returns at once; long tasks run one after another.
    void submit(std::function<void(core::GpuDevice&)> task) { post(std::move(task), /*isLong=*/true); }

    /// From inside a long task (on the GL thread): runs the short tasks waiting now.
    void runShortTasks(core::GpuDevice& device);

    const core::gl::Capabilities& capabilities() const { return m_caps; }

private:
    void post(std::function<void(core::GpuDevice&)> task, bool isLong);
    void loop(std::promise<void>& started);

    std::thread m_thread;
    std::mutex m_mutex;
    std::condition_variable m_wake;
    std::deque<std::function<void(core::GpuDevice&)>> m_short, m_long;
    bool m_stopping = false;
    core::gl::Capabilities m_caps;
};

}  // namespace volstyle::server

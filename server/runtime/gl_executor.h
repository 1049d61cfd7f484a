#pragma once
/// \file gl_executor.h
/// Where a service's GL work runs (SPEC §3 Concurrency): closures that get the GpuDevice. The
/// server's is GlWorker (its one GL thread); tests of the services give a fake that has no GL
/// context at all (tests/service/fake_gl_executor.h), so everything a service does without the
/// GPU is tested without one. Exceptions travel back to the caller.

#include <atomic>
#include <functional>
#include <future>
#include <memory>
#include <string>

#include "core/gl/context.h"
#include "core/gl/gpu_memory.h"
#include "core/gpu/gpu_device.h"

namespace volstyle::server {

/// The GL thread's queue (GET /metrics, /ready).
struct GlQueueDepth {
    size_t shortTasks = 0, longTasks = 0, idleTasks = 0;
    bool stopping = false;
};

class GlExecutor {
public:
    virtual ~GlExecutor() = default;

    /// Runs a short `task(device)` (a render, a release) on the GL thread and returns its
    /// result (or rethrows its exception). Short tasks also run between a long task's iterations.
    template <typename F>
    auto run(F&& task) -> decltype(task(std::declval<core::GpuDevice&>())) {
        return start(std::forward<F>(task)).get();
    }

    /// Queues a short task as run() does and returns at once: its result (or exception) comes
    /// through the future, so the caller can work while the GL thread does (a live stream encodes
    /// one frame while the next renders).
    template <typename F>
    auto start(F&& task) -> std::future<decltype(task(std::declval<core::GpuDevice&>()))> {
        using R = decltype(task(std::declval<core::GpuDevice&>()));
        auto job = std::make_shared<std::packaged_task<R(core::GpuDevice&)>>(std::forward<F>(task));
        auto result = job->get_future();
        m_used = true;
        post([job](core::GpuDevice& r) { (*job)(r); }, /*isLong=*/false);
        return result;
    }

    /// Queues a long task (a solve) and returns at once; long tasks run one after another.
    void submit(std::function<void(core::GpuDevice&)> task) {
        m_used = true;
        post(std::move(task), /*isLong=*/true);
    }

    /// Work done ahead of a request (a solve's renders while the artist paints, solve_prefetch.h):
    /// `task(device, yield)` runs only once the GL thread has had nothing else to do for a moment,
    /// and `yield` is raised as soon as any other task is queued; it should then stop (between
    /// chunks: WorkBudget's cancel flag) and return false, and runs again at the next idle moment.
    /// It returns true once done. Queued under a `key` already waiting, it replaces that task.
    using IdleTask = std::function<bool(core::GpuDevice&, const std::atomic<bool>& yield)>;
    void whenIdle(const std::string& key, IdleTask task) { postIdle(key, std::move(task)); }

    /// Whether any task was ever given to it (a service that never used GL has nothing to free).
    bool used() const { return m_used; }

    /// From inside a long task (on the GL thread): runs the short tasks waiting now.
    virtual void runShortTasks(core::GpuDevice& device) = 0;

    virtual const core::gl::Capabilities& capabilities() const = 0;
    /// Tasks waiting now (a fake executor: none).
    virtual GlQueueDepth queueDepth() const { return {}; }
    /// The GPU memory the driver last reported (read on the GL thread at most once a second, between
    /// tasks; -1 where the driver reports none: capabilities().memoryInfo is then empty).
    virtual core::gl::GpuMemory gpuMemory() const { return {}; }

protected:
    /// Queues `task`; throws (GpuError) when it cannot run at all.
    virtual void post(std::function<void(core::GpuDevice&)> task, bool isLong) = 0;
    /// Queues an idle task (whenIdle); an executor without a GL thread of its own does nothing ahead.
    virtual void postIdle(const std::string& /*key*/, IdleTask /*task*/) {}
    /// An idle task is about to run: GL objects may exist from now on (shutdown frees them).
    void markUsed() { m_used = true; }

private:
    std::atomic<bool> m_used{false};
};

}  // namespace volstyle::server

#include "server/runtime/gl_worker.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>

#include <spdlog/spdlog.h>

#include "core/base/errors.h"

namespace volstyle::server {
namespace {
constexpr auto kTrimInterval = std::chrono::seconds(5);
constexpr auto kGpuMemoryInterval = std::chrono::seconds(1);
/// How long the queues must stand empty before an idle task starts: a live stream's next frame or
/// a page's next request usually comes sooner, and the idle work then waits instead of making it wait.
constexpr auto kQuietBeforeIdle = std::chrono::milliseconds(300);
}  // namespace

void GlWorker::sampleGpuMemory(std::chrono::steady_clock::time_point& last) {
    if (m_caps.memoryInfo.empty() || std::chrono::steady_clock::now() - last < kGpuMemoryInterval) return;
    const core::gl::GpuMemory m = core::gl::queryGpuMemory(m_caps.memoryInfo);
    m_gpuTotal = m.totalBytes;
    m_gpuAvailable = m.availableBytes;
    last = std::chrono::steady_clock::now();
}

GlWorker::GlWorker() {
    std::promise<void> started;
    auto ready = started.get_future();
    m_thread = std::thread([this, &started] { loop(started); });
    try {
        ready.get();
    } catch (...) {
        m_thread.join();
        throw;
    }
}

GlWorker::~GlWorker() {
    {
        std::lock_guard lock(m_mutex);
        m_stopping = true;
        m_yield = true;  // an idle task running stops at its next chunk
        m_idle.clear();  // work ahead is never owed
    }
    m_wake.notify_all();
    if (m_thread.joinable()) m_thread.join();
}

void GlWorker::post(std::function<void(core::GpuDevice&)> task, bool isLong) {
    {
        std::lock_guard lock(m_mutex);
        // A task queued after the thread drained its queues would never run, and whoever waits
        // for it (a live stream freeing its read-back slots as the server stops) would wait for ever.
        if (m_stopping) throw GpuError("the GL thread is stopping");
        (isLong ? m_long : m_short).push_back(std::move(task));
        m_yield = true;  // an idle task running now stops at its next chunk
    }
    m_wake.notify_one();
}

void GlWorker::postIdle(const std::string& key, IdleTask task) {
    {
        std::lock_guard lock(m_mutex);
        if (m_stopping) return;  // work ahead is never owed
        auto it = std::find_if(m_idle.begin(), m_idle.end(), [&](const auto& t) { return t.first == key; });
        if (it != m_idle.end()) it->second = std::move(task);
        else m_idle.emplace_back(key, std::move(task));
    }
    m_wake.notify_one();
}

bool GlWorker::runIdleTask(std::unique_lock<std::mutex>& lock, core::GpuDevice& device) {
    if (m_idle.empty() || m_stopping) return false;
    if (m_wake.wait_for(lock, kQuietBeforeIdle, [&] { return m_stopping || !m_short.empty() || !m_long.empty(); })) return true;
    auto [key, task] = std::move(m_idle.front());
    m_idle.pop_front();
    m_yield = false;
    markUsed();
    lock.unlock();
    bool done = true;
    try {
        done = task(device, m_yield);
    } catch (const std::exception& e) {
        spdlog::warn("work ahead '{}' failed: {}", key, e.what());  // it was never asked for: nobody else to tell
    }
    lock.lock();
    const bool replaced = std::any_of(m_idle.begin(), m_idle.end(), [&](const auto& t) { return t.first == key; });
    if (!done && !replaced && !m_stopping) m_idle.emplace_back(std::move(key), std::move(task));
    return true;
}

void GlWorker::runShortTasks(core::GpuDevice& device) {
    for (;;) {
        std::function<void(core::GpuDevice&)> task;
        {
            std::lock_guard lock(m_mutex);
            if (m_short.empty()) return;
            task = std::move(m_short.front());
            m_short.pop_front();
        }
        task(device);
    }
}

void GlWorker::loop(std::promise<void>& started) {
    std::unique_ptr<core::GpuDevice> device;
    try {
        device = core::GpuDevice::create();
        m_caps = device->capabilities();
        started.set_value();
    } catch (...) {
        started.set_exception(std::current_exception());
        return;
    }
    auto lastTrim = std::chrono::steady_clock::now();
    auto lastMemory = lastTrim - kGpuMemoryInterval;
    sampleGpuMemory(lastMemory);
    for (;;) {
        std::function<void(core::GpuDevice&)> task;
        {
            std::unique_lock lock(m_mutex);
            if (m_short.empty() && m_long.empty() && std::chrono::steady_clock::now() - lastTrim > kTrimInterval) {
                // Going idle: hand the memory freed by renders and solves back to the system.
                // Without it glibc kept it in the arenas (the soak's RSS grew 16% in 10 min;
                // malloc_trim returned 62 MiB of it).
                lock.unlock();
                ::malloc_trim(0);
                lastTrim = std::chrono::steady_clock::now();
                lock.lock();
            }
            if (m_short.empty() && m_long.empty() && runIdleTask(lock, *device)) continue;
            m_wake.wait(lock, [&] { return m_stopping || !m_short.empty() || !m_long.empty() || !m_idle.empty(); });
            auto& queue = !m_short.empty() ? m_short : m_long;  // short tasks first
            if (queue.empty() && !m_stopping) continue;          // woken for an idle task
            if (queue.empty()) break;                            // stopping and drained
            task = std::move(queue.front());
            queue.pop_front();
        }
        task(*device);  // packaged tasks capture their own exceptions
        sampleGpuMemory(lastMemory);
    }
    device.reset();  // GL objects and the context die on this thread
}

GlQueueDepth GlWorker::queueDepth() const {
    std::lock_guard lock(m_mutex);
    return {m_short.size(), m_long.size(), m_idle.size(), m_stopping};
}

}  // namespace volstyle::server

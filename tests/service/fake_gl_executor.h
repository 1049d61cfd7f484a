#pragma once
// A GlExecutor without GL (issue #36): the session services run on it in tests that need no GL
// context. A short task (a render, a release of a GPU copy) answers GpuError naming the test's
// executor; a long task (a solve, a sequence) is kept, never run, so a job stays queued. Both
// are counted, so a test can assert that something needed no GL at all.

#include <atomic>
#include <functional>
#include <mutex>
#include <vector>

#include "core/base/errors.h"
#include "server/runtime/gl_executor.h"

namespace volstyle::test {

class FakeGlExecutor final : public server::GlExecutor {
public:
    struct Counts {
        std::atomic<int> shortTasks{0}, longTasks{0};
    };
    explicit FakeGlExecutor(std::shared_ptr<Counts> counts) : m_counts(std::move(counts)) {}

    void runShortTasks(core::GpuDevice&) override {}
    const core::gl::Capabilities& capabilities() const override { return m_caps; }

private:
    void post(std::function<void(core::GpuDevice&)> task, bool isLong) override {
        if (isLong) {
            ++m_counts->longTasks;
            std::lock_guard lock(m_mutex);
            m_kept.push_back(std::move(task));  // queued for good: its job stays "queued"
            return;
        }
        ++m_counts->shortTasks;
        throw GpuError("this test's GL executor has no GL context");
    }

    std::shared_ptr<Counts> m_counts;
    core::gl::Capabilities m_caps;
    std::mutex m_mutex;
    std::vector<std::function<void(core::GpuDevice&)>> m_kept;
};

}  // namespace volstyle::test

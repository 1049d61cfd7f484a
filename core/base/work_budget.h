#pragma once
/// \file work_budget.h
/// A time budget for GL work that a request can make arbitrarily long (a light-depth volume of a
/// 256³ grid takes minutes on llvmpipe). Long passes run in chunks (chunked_dispatch.h) and call
/// check() between them: past the deadline it throws OverBudget naming the pass and how far it
/// got; a set cancel flag throws Cancelled. The default budget is unlimited and costs nothing.

#include <algorithm>
#include <atomic>
#include <cmath>

#include <cstdio>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"

namespace volstyle {

class WorkBudget {
public:
    WorkBudget() = default;  ///< unlimited, not cancellable
    /// `seconds` from now (<= 0 or infinite: unlimited); `cancel`, if given, is polled by check().
    explicit WorkBudget(double seconds, const std::atomic<bool>* cancel = nullptr)
        : m_start(Clock::now()), m_seconds(seconds > 0 && std::isfinite(seconds) ? seconds : 0), m_cancel(cancel) {}

    /// Whether check() can ever throw (else work need not be chunked).
    bool bounded() const { return m_seconds > 0 || m_cancel; }
    double seconds() const { return m_seconds; }
    /// Chunks `divisor` times smaller than a pass would cut otherwise (at least one invocation):
    /// work done ahead of a request (solve_prefetch.h) must give the GL thread back within a
    /// fraction of a second when one arrives, and a 480² render is one chunk of seconds on llvmpipe.
    /// Relative, so a pass whose invocations each march a whole row (light depth) is cut as finely.
    WorkBudget& withFinerChunks(long long divisor) {
        m_chunkDivisor = std::max(1LL, divisor);
        return *this;
    }
    long long chunkInvocations(long long pass) const { return std::max(1LL, pass / m_chunkDivisor); }

    /// Between chunks of `pass`, `fractionDone` of it finished.
    void check(const char* pass, double fractionDone) const {
        char text[256];
        if (m_cancel && m_cancel->load()) {
            std::snprintf(text, sizeof text, "the %s was cancelled with %.0f%% done", pass, 100 * fractionDone);
            throw Cancelled(text);
        }
        if (m_seconds > 0 && msSince(m_start) > 1000 * m_seconds) {
            std::snprintf(text, sizeof text,
                          "the %s stopped at its time budget of %g s with %.0f%% done; render fewer voxels or "
                          "pixels, or raise the server's --render-budget",
                          pass, m_seconds, 100 * fractionDone);
            throw OverBudget(text);
        }
    }

private:
    Clock::time_point m_start = Clock::now();
    double m_seconds = 0;
    const std::atomic<bool>* m_cancel = nullptr;
    long long m_chunkDivisor = 1;
};

}  // namespace volstyle

#pragma once
/// \file stopwatch.h
/// Wall-clock timing in milliseconds, for stats and progress reports.

#include <chrono>

namespace volstyle {

using Clock = std::chrono::steady_clock;

inline double msSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace volstyle

#pragma once
/// \file request_metrics.h
/// What GET /metrics says about requests (issue #41 item 4), in Prometheus' text format (0.0.4):
/// requests counted by method, route and status, and their latency as a histogram by route. A
/// route is its pattern as a template ("/api/v1/sessions/{}/render"), so the label set stays as
/// small as the route table however many sessions there are. The other figures (sessions, jobs
/// by state, the GL queue, streams, memory) are gauges the route reads when it is scraped.

#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <tuple>

namespace volstyle::server {

/// A route pattern (a regular expression) as a label: each group becomes "{}", escapes drop.
std::string routeLabel(const std::string& pattern);

/// The route label of the request this thread serves ("" before routing, or when none matched).
void setCurrentRoute(const std::string* label);
const std::string* currentRoute();

/// One gauge or counter line: `name{labels} value`, with its HELP and TYPE once per name.
class MetricsText {
public:
    void family(const std::string& name, const std::string& type, const std::string& help);
    void sample(const std::string& name, const std::string& labels, double value);
    const std::string& text() const { return m_text; }

private:
    std::string m_text;
};

/// Prometheus' label value escaping (backslash, double quote, newline).
std::string labelValue(const std::string& value);

class RequestMetrics {
public:
    /// Upper bounds of the latency buckets in seconds (+Inf is implied).
    static constexpr std::array<double, 12> kBuckets{0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30};

    /// One answered request.
    void record(const std::string& method, const std::string& route, int status, double seconds);
    /// The requests counter and the latency histogram.
    void write(MetricsText& out) const;

private:
    struct Latency {
        std::array<uint64_t, kBuckets.size()> buckets{};  ///< per bucket (not cumulative)
        uint64_t count = 0;
        double sum = 0;
    };
    mutable std::mutex m_mutex;
    std::map<std::tuple<std::string, std::string, int>, uint64_t> m_requests;  ///< method, route, status
    std::map<std::string, Latency> m_latency;                                    ///< by route
};

}  // namespace volstyle::server

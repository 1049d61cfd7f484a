#include "server/http/request_metrics.h"

#include <fmt/format.h>

#include <cmath>

namespace volstyle::server {

namespace {
thread_local const std::string* t_route = nullptr;
}

void setCurrentRoute(const std::string* label) { t_route = label; }
const std::string* currentRoute() { return t_route; }

std::string routeLabel(const std::string& pattern) {
    std::string out;
    int depth = 0;
    for (size_t i = 0; i < pattern.size(); ++i) {
        const char ch = pattern[i];
        if (ch == '\\' && i + 1 < pattern.size()) {
            if (depth == 0) out += pattern[i + 1];
            ++i;
        } else if (ch == '(') {
            if (depth++ == 0) out += "{}";
        } else if (ch == ')') {
            --depth;
        } else if (depth == 0) {
            out += ch;
        }
    }
    return out;
}

std::string labelValue(const std::string& value) {
    std::string out;
    for (char ch : value) {
        if (ch == '\\' || ch == '"') out += '\\', out += ch;
        else if (ch == '\n') out += "\\n";
        else out += ch;
    }
    return out;
}

void MetricsText::family(const std::string& name, const std::string& type, const std::string& help) {
    m_text += fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, help, name, type);
}

void MetricsText::sample(const std::string& name, const std::string& labels, double value) {
    const std::string v = std::isinf(value) ? (value > 0 ? "+Inf" : "-Inf") : fmt::format("{}", value);
    m_text += labels.empty() ? fmt::format("{} {}\n", name, v) : fmt::format("{}{{{}}} {}\n", name, labels, v);
}

void RequestMetrics::record(const std::string& method, const std::string& route, int status, double seconds) {
    std::lock_guard lock(m_mutex);
    ++m_requests[{method, route, status}];
    Latency& l = m_latency[route];
    size_t b = 0;
    while (b < kBuckets.size() && seconds > kBuckets[b]) ++b;
    if (b < kBuckets.size()) ++l.buckets[b];
    ++l.count;
    l.sum += seconds;
}

void RequestMetrics::write(MetricsText& out) const {
    std::lock_guard lock(m_mutex);
    out.family("volstyle_http_requests_total", "counter", "HTTP requests answered, by method, route and status");
    for (const auto& [key, n] : m_requests) {
        const auto& [method, route, status] = key;
        out.sample("volstyle_http_requests_total", fmt::format("method=\"{}\",route=\"{}\",status=\"{}\"", method, labelValue(route), status),
                   double(n));
    }
    out.family("volstyle_http_request_duration_seconds", "histogram", "time from a request's head to its answer's last byte, by route");
    for (const auto& [route, l] : m_latency) {
        const std::string r = labelValue(route);
        uint64_t cumulative = 0;
        for (size_t b = 0; b < kBuckets.size(); ++b) {
            cumulative += l.buckets[b];
            out.sample("volstyle_http_request_duration_seconds_bucket", fmt::format("route=\"{}\",le=\"{}\"", r, kBuckets[b]), double(cumulative));
        }
        out.sample("volstyle_http_request_duration_seconds_bucket", fmt::format("route=\"{}\",le=\"+Inf\"", r), double(l.count));
        out.sample("volstyle_http_request_duration_seconds_sum", fmt::format("route=\"{}\"", r), l.sum);
        out.sample("volstyle_http_request_duration_seconds_count", fmt::format("route=\"{}\"", r), double(l.count));
    }
}

}  // namespace volstyle::server

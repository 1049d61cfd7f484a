// Operations (issue #41 item 4): GET /ready (the store takes writes, GL is up, the server is not
// stopping: what a load balancer's health check asks before it sends work) and GET /metrics
// (Prometheus text: requests by route and status, their latency, sessions, jobs by state, the GL
// thread's queue, open streams, memory). GET /health stays the cheap liveness answer.
#include <fmt/format.h>

#include "protocol/build_version.h"
#include "server/http/routes/route_context.h"

namespace volstyle::server {

namespace {

/// The GPU's memory as its driver reports it (read at most once a second on the GL thread), and
/// whether it does: Mesa's llvmpipe reports none, NVIDIA through GL_NVX_gpu_memory_info.
void writeGpuMemory(const GlExecutor& gl, MetricsText& out) {
    const std::string& source = gl.capabilities().memoryInfo;
    out.family("volstyle_gpu_memory_reported", "gauge", "1 when the GL driver reports its memory (through the extension named), else 0");
    out.sample("volstyle_gpu_memory_reported", fmt::format("source=\"{}\"", source.empty() ? "none" : source), source.empty() ? 0 : 1);
    const core::gl::GpuMemory m = gl.gpuMemory();
    if (m.totalBytes < 0 && m.availableBytes < 0) return;
    out.family("volstyle_gpu_memory_bytes", "gauge", "the GPU's memory as its driver reports it: total and available now");
    if (m.totalBytes >= 0) out.sample("volstyle_gpu_memory_bytes", "kind=\"total\"", double(m.totalBytes));
    if (m.availableBytes >= 0) out.sample("volstyle_gpu_memory_bytes", "kind=\"available\"", double(m.availableBytes));
}

/// The gauges read when /metrics is scraped.
void writeGauges(RouteContext& c, MetricsText& out) {
    out.family("volstyle_build_info", "gauge", "the running build (its version as a label)");
    out.sample("volstyle_build_info", fmt::format("version=\"{}\"", labelValue(protocol::versionString())), 1);
    out.family("volstyle_sessions", "gauge", "sessions held");
    out.sample("volstyle_sessions", "", double(c.services.sessions.all().size()));
    std::map<std::string, int> byState;
    for (const auto& [state, name] : protocol::kJobStates) byState[name] = 0;
    for (const auto& j : c.services.jobs.all()) {
        std::lock_guard lock(j->mutex);
        if (!j->remote) ++byState[protocol::jobStateName(j->state)];
    }
    out.family("volstyle_jobs", "gauge", "jobs this server runs or ran, by state (queued ones are its own queue's depth)");
    for (const auto& [name, n] : byState) out.sample("volstyle_jobs", fmt::format("state=\"{}\"", name), n);
    if (auto& queue = c.services.context.queue) {
        std::map<std::string, long long> stored;
        for (const auto& [state, name] : protocol::kJobStates) stored[name] = 0;
        try {
            for (const auto& [state, n] : queue->countByState()) stored[state] = n;
            out.family("volstyle_job_queue", "gauge", "the store's job queue by state, every replica's jobs (queued: its depth)");
            for (const auto& [name, n] : stored) out.sample("volstyle_job_queue", fmt::format("state=\"{}\"", name), double(n));
        } catch (const std::exception&) {
            // The store is down: /ready says so; the other figures still come.
        }
    }
    const GlQueueDepth gl = c.services.context.gl->queueDepth();
    out.family("volstyle_gl_queue", "gauge", "tasks waiting for the GL thread (short: renders and uploads; long: solves; idle: work ahead)");
    out.sample("volstyle_gl_queue", "kind=\"short\"", double(gl.shortTasks));
    out.sample("volstyle_gl_queue", "kind=\"long\"", double(gl.longTasks));
    out.sample("volstyle_gl_queue", "kind=\"idle\"", double(gl.idleTasks));
    out.family("volstyle_prefetched_views_total", "counter",
               "views made ahead of a solve while the GL thread was idle (--prefetch): their renders, and their rows of W");
    out.sample("volstyle_prefetched_views_total", "what=\"renders\"", double(c.services.context.prefetchedViews.load()));
    out.sample("volstyle_prefetched_views_total", "what=\"rows\"", double(c.services.context.prefetchedRows.load()));
    out.family("volstyle_streams_open", "gauge", "event and live streams open");
    out.sample("volstyle_streams_open", "", c.streams.open());
    out.family("volstyle_memory_charged_bytes", "gauge",
               "bytes the memory budget charges the sessions (volumes, frames, images; their GPU copies are the same size)");
    out.sample("volstyle_memory_charged_bytes", "", double(c.services.context.memory.total()));
    out.family("volstyle_memory_limit_bytes", "gauge", "the memory budget of all sessions together");
    out.sample("volstyle_memory_limit_bytes", "", double(c.services.context.memory.limits().total));
    writeGpuMemory(*c.services.context.gl, out);
}

}  // namespace

void addOperationsRoutes(RouteContext& c) {
    c.get(kApi + "/ready", [&c](const httplib::Request&, httplib::Response& res) {
        const SessionsService::Readiness r = c.services.sessions.readiness();
        std::string why = r.storeProblem.empty() ? "" : "the store (" + r.store + ") takes no writes: " + r.storeProblem;
        if (!r.glProblem.empty()) why += (why.empty() ? "" : "; ") + r.glProblem;
        if (c.serving && !c.serving()) why += std::string(why.empty() ? "" : "; ") + "the server is stopping";
        if (!why.empty()) {
            res.set_header("Retry-After", "5");
            throw protocol::ApiError(protocol::ErrorCode::Overloaded, "not ready: " + why);
        }
        reply(res, 200, {{"status", "ready"}, {"store", r.store}, {"gl_renderer", c.services.sessions.capabilities().renderer}});
    });
    c.get(kApi + "/metrics", [&c](const httplib::Request&, httplib::Response& res) {
        MetricsText out;
        if (c.metrics) c.metrics->write(out);
        writeGauges(c, out);
        res.set_content(out.text(), "text/plain; version=0.0.4; charset=utf-8");
    });
}

}  // namespace volstyle::server

#include "server/http/http_server.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include <atomic>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/volume/builtin_scenes.h"
#include "protocol/error_body.h"
#include "protocol/validation.h"
#include "server/http/routes/route_context.h"
#include "server/service/services.h"

namespace volstyle::server {
namespace {

bool isLoopback(const std::string& host) { return host == "127.0.0.1" || host == "localhost" || host == "::1"; }

/// Compares in time independent of where the strings differ.
bool constantTimeEquals(const std::string& a, const std::string& b) {
    unsigned char diff = a.size() == b.size() ? 0 : 1;
    for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i % std::max<size_t>(b.size(), 1)]);
    return diff == 0;
}

/// Retry-After of a 503 when the server's memory budget is full (sessions are deleted by people).
constexpr int kRetryAfterMemorySeconds = 30;

thread_local Clock::time_point t_requestStart;
thread_local std::string t_requestId;

void replyError(httplib::Response& res, protocol::ErrorCode code, const std::string& message,
                const std::vector<protocol::FieldError>& details = {}) {
    reply(res, protocol::httpStatus(code), protocol::errorBody(code, message, details, t_requestId));
}

ServiceLimits serviceLimits(const ServerOptions& o) {
    ServiceLimits l;
    l.maxSessions = o.maxSessions;
    l.maxUploadBytes = o.maxUploadBytes;
    l.maxImageSide = o.maxImageSide;
    l.volumeLimits = o.volumeLimits;
    l.meshLimits.maxVertices = o.maxMeshVertices;
    l.meshLimits.maxTriangles = 2 * o.maxMeshVertices;
    l.renderBudgetSeconds = o.renderBudgetSeconds;
    l.prefetchSolves = o.prefetchSolves;
    l.vdbReader.executable = o.vdbReader;
    l.finishedJobsKept = o.finishedJobsKept;
    l.memory = o.memory;
    l.store = o.store;
    l.replica = o.replica;
    l.jobLease = std::chrono::milliseconds(static_cast<long long>(o.jobLeaseSeconds * 1000));
    return l;
}

protocol::RequestLimits requestLimits(const ServerOptions& o) {
    protocol::RequestLimits l;
    l.maxImageSide = o.maxImageSide;
    l.maxSceneResolution = core::kMaxSceneResolution;
    l.maxSolveVoxels = o.volumeLimits.maxVoxels;
    return l;
}

}  // namespace

struct HttpServer::Impl {
    ServerOptions opt;
    GuardedHttpServer http;
    Services services;
    StreamLimiter streams;
    RouteTable table;
    IdempotencyKeys idempotency;
    RouteContext routes;
    RequestMetrics metrics;
    std::atomic<uint64_t> requestCounter{0};

    explicit Impl(ServerOptions o)
        : opt(std::move(o)),
          http(opt.connections),
          services(serviceLimits(opt), opt.dataDir),
          streams(opt.maxEventStreams, opt.maxEventStreamsPerClient),
          routes{http,  services,    requestLimits(opt), opt.maxJsonBytes, streams, table, idempotency, opt.eventKeepAliveSeconds,
                 &metrics, [this] { return http.serving(); }} {}

    void addMiddleware();
    /// 405 with Allow where the path has routes under other methods (OPTIONS: 204 with Allow),
    /// else 404 naming what is missing.
    void answerNoRoute(const httplib::Request& req, httplib::Response& res);
    /// The SPEC error body for every exception a route throws and every error the library raises itself.
    void addErrorHandlers();
    /// A fresh request id for this thread's request, also sent as X-Request-Id.
    void beginRequest(httplib::Response& res) {
        t_requestStart = Clock::now();
        t_requestId = fmt::format("{:08x}", ++requestCounter);
        res.set_header("X-Request-Id", t_requestId);
    }
};

HttpServer::HttpServer(ServerOptions options) {
    if (!isLoopback(options.host) && options.token.empty())
        throw InvalidArgument("serve: binding " + options.host +
                              " exposes the API beyond this machine; give --token (or VOLSTYLE_TOKEN)");
    m = std::make_unique<Impl>(std::move(options));
    m->addMiddleware();
    addSystemRoutes(m->routes);
    addOperationsRoutes(m->routes);
    addSessionRoutes(m->routes);
    addVolumeRoutes(m->routes);
    addFrameRoutes(m->routes);
    addViewRoutes(m->routes);
    addJobRoutes(m->routes);
    addStylizerRoutes(m->routes);
    addViewportRoutes(m->routes);
    if (!m->opt.webDir.empty()) m->http.set_mount_point("/", m->opt.webDir);  // httplib refuses '..' paths
    m->services.startJobQueue();
}

HttpServer::~HttpServer() {
    stop();
    m->services.stopJobQueue();  // its claims call the routes' resumers: stopped while the routes live
}

int HttpServer::bind() {
    const int port = m->http.bindWithBacklog(m->opt.host, m->opt.port);
    if (port <= 0) throw IoError("serve: cannot listen on " + m->opt.host + ":" + std::to_string(m->opt.port) + " (in use?)");
    return port;
}

void HttpServer::listen() { m->http.listen_after_bind(); }
void HttpServer::stop() { m->http.stopServing(); }

std::vector<RouteEntry> HttpServer::routes() const { return m->table.entries(); }

void HttpServer::Impl::addMiddleware() {
    http.set_payload_max_length(opt.maxUploadBytes + (1 << 20));
    // Connections and requests refused before routing: the SPEC body, and a log line each (the
    // library's logger never sees them).
    http.refusal = [this](Refusal why, const std::string& client, const std::string& detail) {
        const std::string id = fmt::format("{:08x}", ++requestCounter);
        protocol::ErrorCode code = protocol::ErrorCode::InvalidArgument;
        std::string message = detail;
        if (why == Refusal::ClientConnections) {
            code = protocol::ErrorCode::TooManyConnections;
            message = "this client holds " + std::to_string(opt.connections.maxConnectionsPerClient) +
                      " open connections (the limit); close some, or reuse them with keep-alive";
        } else if (why == Refusal::Overloaded) {
            code = protocol::ErrorCode::Overloaded;
            message = "the server is over its queue (" + detail + "); retry after " +
                      std::to_string(opt.connections.retryAfterSeconds) + " s";
        } else if (why == Refusal::TargetTooLong || why == Refusal::HeadTooLarge) {
            code = protocol::ErrorCode::TooLarge;
        }
        spdlog::warn("refused a {} from {}: {} (id={})", why == Refusal::ClientConnections || why == Refusal::Overloaded ? "connection" : "request",
                     client, message, id);
        return protocol::toText(protocol::errorBody(code, message, {}, id));
    };
    http.setWorkerThreads(size_t(std::max(opt.httpThreads, opt.maxEventStreams + 4)));
    addErrorHandlers();

    // Request ids, timing, and the bearer token on /api when one is set.
    http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
        beginRequest(res);
        setCurrentRoute(nullptr);
        // A request with neither Content-Length nor Transfer-Encoding has no body (RFC 9112
        // §6.3); cpp-httplib 0.11 would read a POST's body until the connection closes, so
        // `curl -XPOST …/undo` waited out the read timeout and got a 400. The request object is
        // the library's own (non-const) one, passed here as const.
        if ((req.method == "POST" || req.method == "PUT" || req.method == "PATCH" || req.method == "DELETE") &&
            !req.has_header("Content-Length") && !req.has_header("Transfer-Encoding"))
            const_cast<httplib::Request&>(req).headers.emplace("Content-Length", "0");
        if (!opt.token.empty() && req.path.rfind("/api/", 0) == 0 &&
            !constantTimeEquals(req.get_header_value("Authorization"), "Bearer " + opt.token)) {
            replyError(res, protocol::ErrorCode::Unauthorized, "send 'Authorization: Bearer <token>'");
            return httplib::Server::HandlerResponse::Handled;
        }
        return httplib::Server::HandlerResponse::Unhandled;
    });
    http.set_logger([this](const httplib::Request& req, const httplib::Response& res) {
        const double ms = msSince(t_requestStart);
        spdlog::info("{} {} {} {:.1f} ms id={}", req.method, req.path, res.status, ms, t_requestId);
        // The route's template as the label (the page's files are one label, unmatched paths another).
        const std::string* route = currentRoute();
        metrics.record(req.method, route ? *route : req.path.rfind("/api/", 0) == 0 ? "unmatched" : "page", res.status, ms / 1000);
    });
}

void HttpServer::Impl::answerNoRoute(const httplib::Request& req, httplib::Response& res) {
    const std::vector<std::string> methods = table.methodsAt(req.path);
    if (methods.empty()) {
        replyError(res, protocol::ErrorCode::NotFound, describeMissing(req.method, req.path));
        res.status = 404;
        return;
    }
    std::string allow;
    for (const std::string& m : methods) allow += (allow.empty() ? "" : ", ") + m;
    res.set_header("Allow", allow);
    if (req.method == "OPTIONS") {
        res.status = 204;
        return;
    }
    replyError(res, protocol::ErrorCode::MethodNotAllowed, req.method + " is not a method of " + req.path + "; it has " + allow);
}

void HttpServer::Impl::addErrorHandlers() {
    // One exception handler for every route (cpp-httplib's advice): the SPEC's error body.
    http.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        const protocol::ErrorReport e = protocol::describeException(ep);
        if (protocol::httpStatus(e.code) >= 500)
            spdlog::error("request {}: {}: {}", t_requestId, protocol::errorName(e.code), e.message);
        replyError(res, e.code, e.message, e.details);
        if (e.code == protocol::ErrorCode::Overloaded) res.set_header("Retry-After", std::to_string(kRetryAfterMemorySeconds));
    });
    // Errors the HTTP library raises itself (no route, a body over the payload limit, a URI or
    // headers too long, a bad range or request line) get the SPEC body too.
    http.set_error_handler([this](const httplib::Request& req, httplib::Response& res) {
        if (!res.body.empty()) return;
        if (!res.has_header("X-Request-Id")) beginRequest(res);  // refused before routing began
        const int status = res.status;
        if (status == 404) return answerNoRoute(req, res);
        else if (status == 413 && req.get_header_value("Content-Type").rfind("application/x-www-form-urlencoded", 0) == 0)
            // cpp-httplib parses a form body itself and refuses one over 8 KiB (curl -d's default type).
            replyError(res, protocol::ErrorCode::TooLarge,
                       "a body sent as a form (curl -d) is limited to 8 KiB; send JSON with -H 'Content-Type: application/json'");
        else if (status == 413) replyError(res, protocol::ErrorCode::TooLarge, "the request body is over the server's payload limit");
        else if (status == 414 || status == 431) replyError(res, protocol::ErrorCode::TooLarge, "the request's URI or headers are too long");
        else if (status == 416) replyError(res, protocol::ErrorCode::InvalidArgument, "the requested range cannot be served");
        else if (status >= 400 && status < 500) replyError(res, protocol::ErrorCode::InvalidArgument, "the request is malformed (HTTP " + std::to_string(status) + ")");
        else if (status >= 500) replyError(res, protocol::ErrorCode::InternalError, "the server failed to handle the request");
        res.status = status;  // keep the library's status (replyError sets the code's own)
    });
}

}  // namespace volstyle::server

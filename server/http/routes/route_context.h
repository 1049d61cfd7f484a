#pragma once
/// \file route_context.h
/// What every route file shares: the httplib server to register on, the session services to
/// call, the request limits, and the helpers that read a body and write an answer. Handlers are
/// about twenty lines: parse a protocol request, call the service, reply.

#include <httplib.h>
#include <nlohmann/json.hpp>

#include <functional>
#include <map>
#include <mutex>
#include <string>

#include "core/image/image.h"
#include "core/render/renderer.h"
#include "protocol/requests.h"
#include "server/http/idempotency.h"
#include "server/http/request_metrics.h"
#include "server/http/route_table.h"
#include "server/service/services.h"

namespace volstyle::server {

/// Open event streams, by client address: each holds an HTTP worker thread until its job ends,
/// so they are bounded per client and in all, below the pool's size (/health always has threads).
class StreamLimiter {
public:
    StreamLimiter(int maxTotal, int maxPerClient) : m_maxTotal(maxTotal), m_maxPerClient(maxPerClient) {}
    /// Counts a new stream of `client`; ApiError too_many_streams (429) over a limit.
    void acquire(const std::string& client);
    void release(const std::string& client);
    int open() const;  ///< streams open now, in all

private:
    mutable std::mutex m_mutex;
    std::map<std::string, int> m_open;
    int m_total = 0;
    const int m_maxTotal, m_maxPerClient;
};

struct RouteContext {
    httplib::Server& http;
    Services& services;
    protocol::RequestLimits limits;
    size_t maxJsonBytes = 1 << 20;
    StreamLimiter& streams;
    RouteTable& table;
    IdempotencyKeys& idempotency;
    double eventKeepAliveSeconds = 15;  ///< a quiet job event stream's comment interval
    RequestMetrics* metrics = nullptr;  ///< what GET /metrics reports of requests
    /// Whether the server takes new requests (false while it stops: GET /ready says so).
    std::function<bool()> serving;

    /// The JSON body ({} when empty): 413 over maxJsonBytes, 400 invalid_json.
    nlohmann::json body(const httplib::Request& req) const;

    /// Registers a route with cpp-httplib and in the route table.
    void get(const std::string& pattern, httplib::Server::Handler handler);
    void post(const std::string& pattern, httplib::Server::Handler handler);
    void put(const std::string& pattern, httplib::Server::Handler handler);
    void del(const std::string& pattern, httplib::Server::Handler handler);
    /// A POST that creates a session or a job: an `Idempotency-Key` header makes a retry with the
    /// same body answer what the first request did (idempotency.h).
    void postCreating(const std::string& pattern, httplib::Server::Handler handler);
};

/// Path patterns (regular expressions; the groups are the ids).
inline const std::string kApi = "/api/v1";
inline const std::string kSessionPath = kApi + R"(/sessions/([0-9a-f]+))";
inline const std::string kViewPath = kSessionPath + R"(/views/(v[0-9]+))";
inline const std::string kJobPath = kApi + R"(/jobs/([0-9a-f]+))";

/// Registers PUT `pattern` for a binary upload (a VDB or an image): `handler(req, res, bytes)`.
/// The body is read whatever its Content-Type — curl's --data-binary sends
/// application/x-www-form-urlencoded, which cpp-httplib would parse as a form and refuse over
/// 8 KiB with an empty 413 — and the readers recognise the bytes by their magic numbers.
void putUpload(RouteContext& c, const std::string& pattern,
               std::function<void(const httplib::Request&, httplib::Response&, const std::string&)> handler);

/// Live streams in one response (issue #40): multipart/x-mixed-replace, one part per event (a
/// JPEG frame, a JSON failure or end, an empty keep-alive); an <img> shows the frames as they come.
inline const char* const kMjpegContentType = "multipart/x-mixed-replace; boundary=volstyle-frame";
inline const std::string kMjpegEnd = "--volstyle-frame--\r\n";  ///< after the last part
/// One part: its type, extra header lines ("Name: value\r\n" each) and body.
std::string mjpegPart(const std::string& contentType, const std::string& headers, const std::string& body);

void reply(httplib::Response& res, int status, const nlohmann::json& body);
/// 201 with `body` and `Location: location` (the new resource).
void replyCreated(httplib::Response& res, const std::string& location, const nlohmann::json& body);
/// A file to download: `ETag` (`tag`, or a hash of the bytes; `If-None-Match` with it answers
/// 304 without them) and `Content-Disposition: attachment; filename="…"`.
void replyDownload(const httplib::Request& req, httplib::Response& res, std::string bytes, const std::string& mime,
                   const std::string& filename, const std::string& tag = "");
/// Encodes `image` (PNG: sRGB with `exposure` stops; EXR: linear) as the answer.
void replyImage(httplib::Response& res, const core::Image& image, protocol::ImageFormat format, double exposure = 0);
/// A render as PNG (the beauty, sRGB with `exposure` stops) or layered EXR (docs/FORMATS.md).
void replyImage(httplib::Response& res, const core::RenderLayers& render, protocol::ImageFormat format, double exposure = 0,
                bool exrHalf = true);

// Each file registers the routes of one resource.
void addSystemRoutes(RouteContext& c);   ///< health, schema, scenes
void addSessionRoutes(RouteContext& c);  ///< sessions, lighting, renders
void addVolumeRoutes(RouteContext& c);   ///< volume upload, download, revert
void addFrameRoutes(RouteContext& c);    ///< an animation's frames, its key-frame solve and frame render
void addViewRoutes(RouteContext& c);     ///< views, targets, weights, view renders
void addJobRoutes(RouteContext& c);      ///< solve, jobs, events, previews
void addStylizerRoutes(RouteContext& c); ///< the stylizer's scene, meshes, TF, frames, live stream
void addViewportRoutes(RouteContext& c); ///< the painting page's viewport and its live stream
void addOperationsRoutes(RouteContext& c); ///< /ready and /metrics

}  // namespace volstyle::server

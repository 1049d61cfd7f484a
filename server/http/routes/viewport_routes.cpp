// The painting page's viewport (issue #40 item 4): PUT …/viewport sets its camera and render
// options (POST …/render's body; the format is ignored), GET …/viewport answers its revision, and
// GET …/viewport/stream sends a JPEG frame each time the viewport or what the session shows moves
// (multipart/x-mixed-replace, as the stylizer's live stream; docs/API.md).
#include <fmt/format.h>

#include "protocol/error_body.h"
#include "protocol/response_json.h"
#include "server/http/routes/route_context.h"

namespace volstyle::server {

namespace {

using protocol::ErrorCode;

const std::string kViewportPath = kSessionPath + "/viewport";

/// How long the stream waits for a change before checking its client, and how many such waits
/// pass between keep-alive parts (as the stylizer's stream).
constexpr auto kViewportPoll = std::chrono::milliseconds(500);
constexpr int kPollsPerKeepAlive = 30;

std::string framePart(const ViewportFrame& f) {
    return mjpegPart("image/jpeg",
                     fmt::format("X-Revision: {}\r\nX-Shown: {}\r\nX-Version: {}\r\nX-Width: {}\r\nX-Height: {}\r\nX-Render-Ms: {:.1f}\r\n"
                                 "X-Encode-Ms: {:.1f}\r\n",
                                 f.key.revision, f.key.shown, f.version, f.width, f.height, f.renderMs, f.encodeMs),
                     f.jpeg);
}

void streamViewport(RouteContext& c, httplib::Response& res, std::shared_ptr<Session> s, const std::string& client) {
    c.streams.acquire(client);
    res.set_header("Cache-Control", "no-cache");
    res.set_chunked_content_provider(
        kMjpegContentType,
        [&c, s, sent = ViewportKey{}, idle = 0](size_t, httplib::DataSink& sink) mutable {
            std::string part;
            ViewportKey attempted = sent;
            try {
                if (auto f = c.services.viewport.next(*s, sent, kViewportPoll, &attempted)) {
                    sent = f->key;
                    idle = 0;
                    part = framePart(*f);
                } else if (++idle % kPollsPerKeepAlive == 0) {
                    part = mjpegPart("text/plain", "", "");
                }
            } catch (...) {
                const protocol::ErrorReport e = protocol::describeException(std::current_exception());
                if (e.code == ErrorCode::NotFound) {  // the session was deleted
                    const std::string end = mjpegPart("application/json", "", protocol::toText({{"event", "closed"}, {"reason", e.message}})) + kMjpegEnd;
                    sink.write(end.data(), end.size());
                    sink.done();
                    return true;
                }
                // A frame that could not render: said once, and the stream waits past it (a move
                // made while it rendered has a newer key, and renders next).
                sent = attempted;
                part = mjpegPart("application/json", fmt::format("X-Revision: {}\r\n", sent.revision),
                                 protocol::toText({{"event", "failed"}, {"revision", sent.revision},
                                                   {"error", protocol::errorBody(e.code, e.message, e.details, "")["error"]}}));
            }
            if (!part.empty() && !sink.write(part.data(), part.size())) return false;  // the client left
            return sink.is_writable();
        },
        [&c, client](bool) { c.streams.release(client); });
}

}  // namespace

void addViewportRoutes(RouteContext& c) {
    c.put(kViewportPath, [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const ViewportKey k = c.services.viewport.set(*s, protocol::RenderRequest::fromJson(c.body(req), c.limits));
        reply(res, 200, {{"revision", k.revision}, {"shown", k.shown}});
    });
    c.get(kViewportPath, [&c](const httplib::Request& req, httplib::Response& res) {
        const ViewportKey k = c.services.viewport.current(*c.services.sessions.find(req.matches[1]));
        reply(res, 200, {{"revision", k.revision}, {"shown", k.shown}});
    });
    c.get(kViewportPath + "/stream", [&c](const httplib::Request& req, httplib::Response& res) {
        streamViewport(c, res, c.services.sessions.find(req.matches[1]), req.remote_addr);
    });
}

}  // namespace volstyle::server

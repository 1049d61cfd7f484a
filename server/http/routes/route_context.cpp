#include "server/http/routes/route_context.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/image/image_io.h"
#include "core/image/jpeg_encoder.h"
#include "core/render/exr_layers.h"
#include "core/base/content_hash.h"
#include "server/http/request_metrics.h"
#include "server/state/stylizer_state.h"

namespace volstyle::server {

namespace {

/// The handler, telling the metrics which route answers (request_metrics.h).
httplib::Server::Handler labelled(const std::string& pattern, httplib::Server::Handler handler) {
    return [label = std::make_shared<const std::string>(routeLabel(pattern)), handler = std::move(handler)](const httplib::Request& req,
                                                                                                          httplib::Response& res) {
        setCurrentRoute(label.get());
        handler(req, res);
    };
}

}  // namespace

nlohmann::json RouteContext::body(const httplib::Request& req) const { return protocol::parseJsonBody(req.body, maxJsonBytes); }

void RouteContext::get(const std::string& pattern, httplib::Server::Handler handler) {
    table.add("GET", pattern);
    http.Get(pattern, labelled(pattern, std::move(handler)));
}

void RouteContext::post(const std::string& pattern, httplib::Server::Handler handler) {
    table.add("POST", pattern);
    http.Post(pattern, labelled(pattern, std::move(handler)));
}

void RouteContext::put(const std::string& pattern, httplib::Server::Handler handler) {
    table.add("PUT", pattern);
    http.Put(pattern, labelled(pattern, std::move(handler)));
}

void RouteContext::del(const std::string& pattern, httplib::Server::Handler handler) {
    table.add("DELETE", pattern);
    http.Delete(pattern, labelled(pattern, std::move(handler)));
}

namespace {

/// 1-255 visible ASCII characters (the IETF draft's key is an sf-string; clients send UUIDs).
bool isIdempotencyKey(const std::string& key) {
    return !key.empty() && key.size() <= 255 && std::all_of(key.begin(), key.end(), [](char ch) { return ch > ' ' && ch < 127; });
}

}  // namespace

void RouteContext::postCreating(const std::string& pattern, httplib::Server::Handler handler) {
    post(pattern, [this, handler = std::move(handler)](const httplib::Request& req, httplib::Response& res) {
        if (!req.has_header("Idempotency-Key")) return handler(req, res);
        const std::string key = req.get_header_value("Idempotency-Key");
        if (!isIdempotencyKey(key))
            throw protocol::ApiError(protocol::ErrorCode::InvalidArgument, "Idempotency-Key must be 1-255 visible ASCII characters (a UUID)",
                                     {{"Idempotency-Key", "must be 1-255 visible ASCII characters"}});
        const std::string scope = req.method + " " + req.path + " " + key;
        if (std::optional<KeptAnswer> kept = idempotency.claim(scope, contentHash(req.body))) {
            res.status = kept->status;
            res.set_content(kept->body, kept->contentType);
            if (!kept->location.empty()) res.set_header("Location", kept->location);
            res.set_header("Idempotent-Replayed", "true");
            return;
        }
        try {
            handler(req, res);
        } catch (...) {
            idempotency.abandon(scope);  // a retry runs it again
            throw;
        }
        if (res.status >= 200 && res.status < 300)
            idempotency.finish(scope, {res.status, res.body, res.get_header_value("Content-Type"), res.get_header_value("Location")});
        else
            idempotency.abandon(scope);
    });
}

void StreamLimiter::acquire(const std::string& client) {
    std::lock_guard lock(m_mutex);
    int& mine = m_open[client];
    if (mine >= m_maxPerClient || m_total >= m_maxTotal) {
        const bool own = mine >= m_maxPerClient;
        if (mine == 0) m_open.erase(client);
        throw protocol::ApiError(protocol::ErrorCode::TooManyStreams,
                                 own ? "this client has " + std::to_string(m_maxPerClient) + " event streams open (the limit); close one first"
                                     : "the server has " + std::to_string(m_maxTotal) + " event streams open (the limit); try again when a job ends");
    }
    ++mine;
    ++m_total;
}

int StreamLimiter::open() const {
    std::lock_guard lock(m_mutex);
    return m_total;
}

void StreamLimiter::release(const std::string& client) {
    std::lock_guard lock(m_mutex);
    auto it = m_open.find(client);
    if (it == m_open.end()) return;
    if (--it->second == 0) m_open.erase(it);
    --m_total;
}

void putUpload(RouteContext& c, const std::string& pattern,
               std::function<void(const httplib::Request&, httplib::Response&, const std::string&)> handler) {
    c.table.add("PUT", pattern);
    c.http.Put(pattern, [handler = std::move(handler), label = std::make_shared<const std::string>(routeLabel(pattern))](
                            const httplib::Request& req, httplib::Response& res, const httplib::ContentReader& reader) {
        setCurrentRoute(label.get());
        if (req.is_multipart_form_data()) {
            res.set_header("Connection", "close");  // the form's bytes are not read
            throw protocol::ApiError(protocol::ErrorCode::UnsupportedMedia,
                                     "send the file itself as the request body (curl --data-binary @FILE), not as a form (-F)");
        }
        std::string bytes;
        const bool complete = reader([&](const char* data, size_t n) {
            bytes.append(data, n);
            return true;
        });
        if (!complete) {
            res.set_header("Connection", "close");
            if (res.status == 413)
                throw protocol::ApiError(protocol::ErrorCode::TooLarge, "the upload is over the server's upload limit (volstyle serve --max-upload-mib)");
            throw protocol::ApiError(protocol::ErrorCode::InvalidArgument, "the upload ended before its declared length");
        }
        handler(req, res, bytes);
    });
}

void reply(httplib::Response& res, int status, const nlohmann::json& body) {
    res.status = status;
    res.set_content(protocol::toText(body), "application/json");
}

void replyCreated(httplib::Response& res, const std::string& location, const nlohmann::json& body) {
    res.set_header("Location", location);
    reply(res, 201, body);
}

void replyDownload(const httplib::Request& req, httplib::Response& res, std::string bytes, const std::string& mime,
                   const std::string& filename, const std::string& tag) {
    const std::string etag = "\"" + (tag.empty() ? fmt::format("{:016x}", contentHash(bytes)) : tag) + "\"";
    res.set_header("ETag", etag);
    res.set_header("Content-Disposition", "attachment; filename=\"" + filename + "\"");
    // If-None-Match: a list of entity tags (weak ones compare by their opaque part), or *.
    const std::string match = req.get_header_value("If-None-Match");
    for (size_t start = 0; start < match.size();) {
        size_t end = match.find(',', start);
        if (end == std::string::npos) end = match.size();
        std::string tag = match.substr(start, end - start);
        tag.erase(0, tag.find_first_not_of(" \t"));
        tag.erase(tag.find_last_not_of(" \t") + 1);
        if (tag.rfind("W/", 0) == 0) tag.erase(0, 2);
        if (tag == etag || tag == "*") {
            res.status = 304;
            return;
        }
        start = end + 1;
    }
    res.set_content(std::move(bytes), mime);
}

std::string mjpegPart(const std::string& contentType, const std::string& headers, const std::string& body) {
    return fmt::format("--volstyle-frame\r\nContent-Type: {}\r\nContent-Length: {}\r\n{}\r\n", contentType, body.size(), headers) + body +
           "\r\n";
}

void replyImage(httplib::Response& res, const core::Image& image, protocol::ImageFormat format, double exposure) {
    if (format == protocol::ImageFormat::Jpeg) {  // libjpeg-turbo in memory: 4× OpenImageIO's path through a file
        res.set_content(core::encodeJpeg(image, kLiveJpegQuality, exposure), protocol::imageMimeType(format));
        return;
    }
    core::SaveOptions save;
    save.exposure = format != protocol::ImageFormat::Exr ? exposure : 0;  // EXR stays linear
    res.set_content(core::encodeImage(image, protocol::imageFormatName(format), save), protocol::imageMimeType(format));
}

void replyImage(httplib::Response& res, const core::RenderLayers& render, protocol::ImageFormat format, double exposure,
                bool exrHalf) {
    if (format != protocol::ImageFormat::Exr) return replyImage(res, render.beauty, format, exposure);
    res.set_content(core::encodeExrLayers(core::exrLayersOf(render), exrHalf), protocol::imageMimeType(format));
}

}  // namespace volstyle::server

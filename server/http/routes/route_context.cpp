#include "server/http/routes/route_context.h"

#include "core/image/image_io.h"
#include "core/render/exr_layers.h"

namespace volstyle::server {

nlohmann::json RouteContext::body(const httplib::Request& req) const { return protocol::parseJsonBody(req.body, maxJsonBytes); }

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

void StreamLimiter::release(const std::string& client) {
    std::lock_guard lock(m_mutex);
    auto it = m_open.find(client);
    if (it == m_open.end()) return;
    if (--it->second == 0) m_open.erase(it);
    --m_total;
}

void putUpload(RouteContext& c, const std::string& pattern,
               std::function<void(const httplib::Request&, httplib::Response&, const std::string&)> handler) {
    c.http.Put(pattern, [handler = std::move(handler)](const httplib::Request& req, httplib::Response& res,
                                                       const httplib::ContentReader& reader) {
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

void replyImage(httplib::Response& res, const core::Image& image, protocol::ImageFormat format, double exposure) {
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

#include "server/routes/route_context.h"

#include "core/image/image_io.h"

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

void reply(httplib::Response& res, int status, const nlohmann::json& body) {
    res.status = status;
    res.set_content(protocol::toText(body), "application/json");
}

void replyImage(httplib::Response& res, const core::Image& image, protocol::ImageFormat format, double exposure) {
    core::SaveOptions save;
    save.exposure = format == protocol::ImageFormat::Png ? exposure : 0;  // EXR stays linear
    res.set_content(core::encodeImage(image, protocol::imageFormatName(format), save), protocol::imageMimeType(format));
}

}  // namespace volstyle::server

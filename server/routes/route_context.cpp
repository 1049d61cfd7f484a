#include "server/routes/route_context.h"

#include "core/image/image_io.h"

namespace volstyle::server {

nlohmann::json RouteContext::body(const httplib::Request& req) const {
    using protocol::ApiError, protocol::ErrorCode;
    if (req.body.size() > maxJsonBytes)
        throw ApiError(ErrorCode::TooLarge, "the JSON body is " + std::to_string(req.body.size()) +
                                                " bytes; the limit is " + std::to_string(maxJsonBytes));
    if (req.body.empty()) return nlohmann::json::object();
    try {
        return nlohmann::json::parse(req.body);
    } catch (const nlohmann::json::exception& e) {  // parse_error, and out_of_range for numbers like 1e400
        throw ApiError(ErrorCode::InvalidJson, std::string("the body is not valid JSON: ") + e.what());
    }
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

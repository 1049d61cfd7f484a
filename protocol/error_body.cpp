#include "protocol/error_body.h"

namespace volstyle::protocol {

nlohmann::json errorBody(const std::string& code, const std::string& message,
                         const std::vector<FieldError>& details, const std::string& requestId) {
    nlohmann::json d = nlohmann::json::array();
    for (const auto& e : details) d.push_back({{"path", e.path}, {"message", e.message}});
    return {{"error", {{"code", code}, {"message", message}, {"details", d}, {"request_id", requestId}}}};
}

int httpStatusFor(const std::string& code) {
    if (code == "invalid_argument" || code == "unknown_field" || code == "invalid_json") return 400;
    if (code == "unauthorized") return 401;
    if (code == "not_found") return 404;
    if (code == "busy" || code == "cancelled") return 409;
    if (code == "too_large") return 413;
    if (code == "unsupported_media" || code == "io_error" || code == "too_many_jobs" || code == "too_many_sessions")
        return 422;
    if (code == "out_of_memory") return 507;
    return 500;
}

}  // namespace volstyle::protocol

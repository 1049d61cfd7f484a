#include "protocol/error_body.h"

#include "core/base/errors.h"

namespace volstyle::protocol {

ErrorCode errorCodeFromName(std::string_view name) {
    for (const auto& e : kErrorCodes)
        if (name == e.name) return e.code;
    return ErrorCode::InternalError;
}

nlohmann::json errorBody(ErrorCode code, const std::string& message, const std::vector<FieldError>& details,
                         const std::string& requestId) {
    nlohmann::json d = nlohmann::json::array();
    for (const auto& e : details) d.push_back({{"path", e.path}, {"message", e.message}});
    return {{"error", {{"code", errorName(code)}, {"message", message}, {"details", d}, {"request_id", requestId}}}};
}

ErrorReport describeException(std::exception_ptr error) {
    ErrorReport r;
    try {
        std::rethrow_exception(error);
    } catch (const ApiError& e) {
        r = {e.code(), e.what(), e.details()};
    } catch (const ValidationError& e) {
        r = {e.onlyUnknownFields() ? ErrorCode::UnknownField : ErrorCode::InvalidArgument, e.what(), e.details()};
    } catch (const Error& e) {
        r = {errorCodeFromName(e.code()), e.what(), {}};
    } catch (const std::exception& e) {
        r.message = e.what();
    } catch (...) {
    }
    return r;
}

}  // namespace volstyle::protocol

#pragma once
/// \file error_body.h
/// The one error answer of the API (SPEC §3):
/// {"error": {"code": "snake_case", "message": "what and how to fix", "details": [{"path", "message"}],
///            "request_id": "…"}}, and the translation of any exception into it.

#include <nlohmann/json.hpp>

#include <exception>
#include <string>
#include <vector>

#include "protocol/error_code.h"
#include "protocol/validation.h"

namespace volstyle::protocol {

nlohmann::json errorBody(ErrorCode code, const std::string& message, const std::vector<FieldError>& details,
                         const std::string& requestId);

/// What an exception means to the API: its code, message and field details. ApiError and
/// ValidationError carry theirs; core's errors map by code(); anything else is internal_error.
struct ErrorReport {
    ErrorCode code = ErrorCode::InternalError;
    std::string message = "unexpected error";
    std::vector<FieldError> details;
};
ErrorReport describeException(std::exception_ptr error);

}  // namespace volstyle::protocol

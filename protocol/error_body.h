#pragma once
/// \file error_body.h
/// The one error answer of the API (SPEC §3):
/// {"error": {"code": "snake_case", "message": "what and how to fix", "details": [{"path", "message"}],
///            "request_id": "…"}}, and the HTTP status of each code.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "protocol/validation.h"

namespace volstyle::protocol {

nlohmann::json errorBody(const std::string& code, const std::string& message,
                         const std::vector<FieldError>& details, const std::string& requestId);

/// 400 invalid_argument/unknown_field/invalid_json, 401 unauthorized, 404 not_found, 409 busy/
/// cancelled, 413 too_large, 422 unsupported_media, 500 gpu_error/internal_error/…, 507 out_of_memory.
int httpStatusFor(const std::string& code);

}  // namespace volstyle::protocol

#pragma once
/// \file error_code.h
/// The closed set of error codes the API answers with (SPEC §3), each with its snake_case name
/// and HTTP status in one constexpr table; core's exceptions map onto it by their code() names.
/// The schema (protocol/schema/v1.json) and docs/API.md list the same names; a unit test checks.

#include <nlohmann/json.hpp>

#include <iterator>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace volstyle::protocol {

enum class ErrorCode {
    InvalidArgument,     ///< a field or parameter is wrong (details name each)
    UnknownField,        ///< every problem is a field the request type does not have
    InvalidJson,         ///< the body does not parse
    Unauthorized,        ///< the bearer token is missing or wrong
    NotFound,            ///< no such route, session, view, job or version
    MethodNotAllowed,    ///< the path has routes, none under this method (the answer's Allow lists them)
    Busy,                ///< the resource is in use
    IdempotencyConflict, ///< an Idempotency-Key used again with another body
    Cancelled,           ///< the job was cancelled
    TooLarge,            ///< a body, upload or volume over its limit (the message names it)
    UnsupportedMedia,    ///< an upload that is not a readable image or VDB
    IoError,             ///< a file could not be read or written
    TooManyJobs,         ///< the session's queue is at its limit
    TooManySessions,     ///< the server holds its session limit
    TooManyStreams,      ///< the client (or the server) holds its limit of open event streams
    TooManyConnections,  ///< the client holds its limit of open connections
    OverBudget,          ///< a render stopped at the server's time budget
    Overloaded,          ///< the server's queue or memory budget is full: retry after Retry-After seconds
    OutOfBudget,         ///< the session's or the server's memory budget cannot hold what was sent
    Interrupted,         ///< the server stopped while the job was queued or running
    GpuError,            ///< the GL context or driver failed
    ShaderCompileError,  ///< a kernel did not compile (a bug or a driver problem)
    OutOfMemory,         ///< the GPU ran out of memory
    InternalError,       ///< a broken invariant: a bug
};

struct ErrorCodeInfo {
    ErrorCode code;
    const char* name;
    int httpStatus;
};

inline constexpr ErrorCodeInfo kErrorCodes[] = {
    {ErrorCode::InvalidArgument, "invalid_argument", 400},
    {ErrorCode::UnknownField, "unknown_field", 400},
    {ErrorCode::InvalidJson, "invalid_json", 400},
    {ErrorCode::Unauthorized, "unauthorized", 401},
    {ErrorCode::NotFound, "not_found", 404},
    {ErrorCode::MethodNotAllowed, "method_not_allowed", 405},
    {ErrorCode::Busy, "busy", 409},
    {ErrorCode::IdempotencyConflict, "idempotency_conflict", 422},
    {ErrorCode::Cancelled, "cancelled", 409},
    {ErrorCode::TooLarge, "too_large", 413},
    {ErrorCode::UnsupportedMedia, "unsupported_media", 422},
    {ErrorCode::IoError, "io_error", 422},
    {ErrorCode::TooManyJobs, "too_many_jobs", 422},
    {ErrorCode::TooManySessions, "too_many_sessions", 422},
    {ErrorCode::TooManyStreams, "too_many_streams", 429},
    {ErrorCode::TooManyConnections, "too_many_connections", 429},
    {ErrorCode::OverBudget, "over_budget", 422},
    {ErrorCode::Overloaded, "overloaded", 503},
    {ErrorCode::OutOfBudget, "memory_budget", 507},
    {ErrorCode::Interrupted, "interrupted", 500},
    {ErrorCode::GpuError, "gpu_error", 500},
    {ErrorCode::ShaderCompileError, "shader_compile_error", 500},
    {ErrorCode::OutOfMemory, "out_of_memory", 507},
    {ErrorCode::InternalError, "internal_error", 500},
};
static_assert(std::size(kErrorCodes) == size_t(ErrorCode::InternalError) + 1, "a row for every code");

constexpr const ErrorCodeInfo& errorInfo(ErrorCode code) {
    for (const auto& e : kErrorCodes)
        if (e.code == code) return e;
    return kErrorCodes[std::size(kErrorCodes) - 1];
}
constexpr const char* errorName(ErrorCode code) { return errorInfo(code).name; }
constexpr int httpStatus(ErrorCode code) { return errorInfo(code).httpStatus; }
/// The code of a core exception's code() name; InternalError for a name not in the table.
ErrorCode errorCodeFromName(std::string_view name);

/// A field-level problem: the JSON Pointer of the field (or `?name` for a query parameter).
struct FieldError {
    std::string path;
    std::string message;
};

/// An error with its API code, raised by protocol's request types and the server's handlers.
class ApiError : public std::runtime_error {
public:
    ApiError(ErrorCode code, const std::string& message, std::vector<FieldError> details = {})
        : std::runtime_error(message), m_code(code), m_details(std::move(details)) {}
    ErrorCode code() const { return m_code; }
    const std::vector<FieldError>& details() const { return m_details; }

private:
    ErrorCode m_code;
    std::vector<FieldError> m_details;
};

}  // namespace volstyle::protocol

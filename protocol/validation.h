#pragma once
/// \file validation.h
/// Field-level validation of JSON requests: every problem is collected with its JSON Pointer
/// (`/camera/fov_y_deg`) so one answer lists them all (SPEC §3).

#include <nlohmann/json.hpp>

#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "core/base/errors.h"
#include "core/math/vec.h"
#include "protocol/error_code.h"

namespace volstyle::protocol {

constexpr const char* kApiVersion = "v1";

/// The JSON Schema of API v1 (protocol/schema/v1.json, embedded at build time), served at
/// /api/v1/schema.json.
extern const char* const kSchemaV1;

/// Thrown when a request has invalid fields; `details()` lists each. `code()` is
/// "unknown_field" when every problem is an unknown field, "invalid_argument" otherwise.
class ValidationError : public InvalidArgument {
public:
    explicit ValidationError(std::vector<FieldError> details);
    const std::vector<FieldError>& details() const { return m_details; }
    bool onlyUnknownFields() const { return m_onlyUnknownFields; }
    const char* code() const noexcept override;

private:
    std::vector<FieldError> m_details;
    bool m_onlyUnknownFields = false;
};

/// Reads typed values out of JSON, recording a FieldError instead of throwing.
class JsonReader {
public:
    /// Checks `j` is an object whose keys are all in `allowed`; records each unknown key.
    bool object(const nlohmann::json& j, const std::string& path, std::initializer_list<const char*> allowed);
    std::optional<double> number(const nlohmann::json& j, const std::string& path);
    std::optional<int> integer(const nlohmann::json& j, const std::string& path);
    std::optional<std::string> string(const nlohmann::json& j, const std::string& path);
    std::optional<bool> boolean(const nlohmann::json& j, const std::string& path);
    std::optional<Vec3d> vec3(const nlohmann::json& j, const std::string& path);
    void fail(const std::string& path, const std::string& message) { m_errors.push_back({path, message}); }
    /// Records a value check (`path` + "/" + `field`) unless that field, or one it `dependsOn`,
    /// already failed to read: the check would then be about a default, not the input. So every
    /// problem of a body is reported at once, and none twice.
    void check(const std::string& path, const std::string& field, const std::string& message,
               std::initializer_list<const char*> dependsOn = {});
    bool failed(const std::string& path) const;  ///< a problem was recorded at `path` or below it

    bool ok() const { return m_errors.empty(); }
    /// Throws ValidationError if anything was recorded.
    void throwIfErrors() const;
    const std::vector<FieldError>& errors() const { return m_errors; }

private:
    std::vector<FieldError> m_errors;
};

/// A number at `path` within [lo, hi], or `fallback` (a failure is recorded: "must be in [lo, hi]").
double boundedNumber(JsonReader& r, const nlohmann::json& j, const std::string& path, double lo, double hi, double fallback);

/// JSON text of `j`. Invalid UTF-8 in any string (echoed from a request: a path, a field, a
/// parser message) becomes U+FFFD instead of throwing: an answer must always be writable.
std::string toText(const nlohmann::json& j, int indent = -1);

/// A request's JSON body ({} when empty): ApiError too_large over `maxBytes`, invalid_json when it
/// does not parse (including numbers beyond double range, e.g. 1e400).
nlohmann::json parseJsonBody(const std::string& body, size_t maxBytes);

/// Parses JSON text, throwing ValidationError (path "") with the parser's message.
nlohmann::json parseJson(const std::string& text, const std::string& what);

}  // namespace volstyle::protocol

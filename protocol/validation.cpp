#include "protocol/validation.h"

#include <cmath>
#include <cstdint>
#include <limits>

namespace volstyle::protocol {
namespace {

/// Every problem, in one line (a CLI user sees only this; the API also sends `details`), up to a
/// bound that keeps a hostile body's thousand errors out of the logs.
constexpr size_t kSummarized = 16;

std::string summarize(const std::vector<FieldError>& details) {
    std::string s;
    for (size_t i = 0; i < details.size() && i < kSummarized; ++i)
        s += (i ? "; " : "") + (details[i].path.empty() ? std::string("(document)") : details[i].path) + ": " +
             details[i].message;
    if (details.size() > kSummarized) s += "; and " + std::to_string(details.size() - kSummarized) + " more";
    return s;
}

const char* typeName(const nlohmann::json& j) { return j.type_name(); }

}  // namespace

ValidationError::ValidationError(std::vector<FieldError> details)
    : InvalidArgument(summarize(details)), m_details(std::move(details)) {
    m_onlyUnknownFields = !m_details.empty();
    for (const auto& d : m_details) m_onlyUnknownFields &= d.message.rfind("unknown field", 0) == 0;
}

const char* ValidationError::code() const noexcept {
    return m_onlyUnknownFields ? "unknown_field" : "invalid_argument";
}

bool JsonReader::object(const nlohmann::json& j, const std::string& path,
                        std::initializer_list<const char*> allowed) {
    if (!j.is_object()) {
        fail(path, std::string("must be an object, got ") + typeName(j));
        return false;
    }
    for (const auto& [key, value] : j.items()) {
        bool known = false;
        for (const char* a : allowed) known |= key == a;
        if (!known) {
            std::string list;
            for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
            fail(path + "/" + key, "unknown field; allowed: " + list);
        }
    }
    return true;
}

std::optional<double> JsonReader::number(const nlohmann::json& j, const std::string& path) {
    if (!j.is_number()) {
        fail(path, std::string("must be a number, got ") + typeName(j));
        return std::nullopt;
    }
    double v = j.get<double>();
    if (!std::isfinite(v)) {
        fail(path, "must be finite");
        return std::nullopt;
    }
    return v;
}

std::optional<int> JsonReader::integer(const nlohmann::json& j, const std::string& path) {
    if (!j.is_number_integer()) {
        fail(path, std::string("must be an integer, got ") + typeName(j));
        return std::nullopt;
    }
    // Read wide, then range-check: get<int>() would wrap 4294967360 to 64.
    const bool fits = j.is_number_unsigned() ? j.get<uint64_t>() <= uint64_t(std::numeric_limits<int>::max())
                                             : j.get<int64_t>() >= std::numeric_limits<int>::min() &&
                                                   j.get<int64_t>() <= std::numeric_limits<int>::max();
    if (!fits) {
        fail(path, "must be an integer in [" + std::to_string(std::numeric_limits<int>::min()) + ", " +
                       std::to_string(std::numeric_limits<int>::max()) + "]");
        return std::nullopt;
    }
    return int(j.get<int64_t>());
}

std::optional<std::string> JsonReader::string(const nlohmann::json& j, const std::string& path) {
    if (!j.is_string()) {
        fail(path, std::string("must be a string, got ") + typeName(j));
        return std::nullopt;
    }
    return j.get<std::string>();
}

std::optional<bool> JsonReader::boolean(const nlohmann::json& j, const std::string& path) {
    if (!j.is_boolean()) {
        fail(path, std::string("must be true or false, got ") + typeName(j));
        return std::nullopt;
    }
    return j.get<bool>();
}

std::optional<Vec3d> JsonReader::vec3(const nlohmann::json& j, const std::string& path) {
    if (!j.is_array() || j.size() != 3) {
        fail(path, std::string("must be an array of 3 numbers, got ") + typeName(j));
        return std::nullopt;
    }
    Vec3d v;
    bool good = true;
    for (int i = 0; i < 3; ++i) {
        auto c = number(j[size_t(i)], path + "/" + std::to_string(i));
        good &= c.has_value();
        if (c) v[i] = *c;
    }
    return good ? std::optional<Vec3d>(v) : std::nullopt;
}

bool JsonReader::failed(const std::string& path) const {
    for (const auto& e : m_errors)
        if (e.path == path || e.path.rfind(path + "/", 0) == 0) return true;
    return false;
}

void JsonReader::check(const std::string& path, const std::string& field, const std::string& message,
                       std::initializer_list<const char*> dependsOn) {
    const std::string at = path + "/" + field;
    if (failed(at)) return;
    for (const char* other : dependsOn)
        if (failed(path + "/" + other)) return;
    fail(at, message);
}

void JsonReader::throwIfErrors() const {
    if (!m_errors.empty()) throw ValidationError(m_errors);
}

std::string toText(const nlohmann::json& j, int indent) {
    return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

nlohmann::json parseJson(const std::string& text, const std::string& what) {
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw ValidationError({{"", what + " is not valid JSON: " + e.what()}});
    }
}

nlohmann::json parseJsonBody(const std::string& body, size_t maxBytes) {
    if (body.size() > maxBytes)
        throw ApiError(ErrorCode::TooLarge, "the JSON body is " + std::to_string(body.size()) + " bytes; the limit is " +
                                                std::to_string(maxBytes));
    if (body.empty()) return nlohmann::json::object();
    try {
        return nlohmann::json::parse(body);
    } catch (const nlohmann::json::exception& e) {  // parse_error, and out_of_range for numbers like 1e400
        throw ApiError(ErrorCode::InvalidJson, std::string("the body is not valid JSON: ") + e.what());
    }
}

/// A number at `path` within [lo, hi], or `fallback` (a failure is recorded).
double boundedNumber(JsonReader& r, const nlohmann::json& j, const std::string& path, double lo, double hi, double fallback) {
    auto v = r.number(j, path);
    if (!v) return fallback;
    if (!(*v >= lo && *v <= hi)) {
        // Whole bounds print as integers ("[0, 150]", not "[0.0, 150.0]").
        auto text = [](double v) { return v == std::floor(v) && std::abs(v) < 1e15 ? std::to_string(static_cast<long long>(v)) : nlohmann::json(v).dump(); };
        r.fail(path, "must be in [" + text(lo) + ", " + text(hi) + "]");
        return fallback;
    }
    return *v;
}

}  // namespace volstyle::protocol

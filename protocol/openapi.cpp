#include "protocol/openapi.h"

#include <nlohmann/json.hpp>

#include "protocol/validation.h"

namespace volstyle::protocol {

extern const char* const kOpenApiPaths;

namespace {

/// The schema's references ("#/definitions/x") as the document's ("#/components/schemas/x").
void moveReferences(nlohmann::json& j) {
    if (j.is_object()) {
        for (auto& [key, value] : j.items()) {
            if (key == "$ref" && value.is_string()) {
                std::string ref = value;
                const std::string from = "#/definitions/";
                if (ref.rfind(from, 0) == 0) value = "#/components/schemas/" + ref.substr(from.size());
            } else {
                moveReferences(value);
            }
        }
    } else if (j.is_array()) {
        for (auto& value : j) moveReferences(value);
    }
}

}  // namespace

const std::string& openApiDocument() {
    static const std::string text = [] {
        nlohmann::json doc = nlohmann::json::parse(kOpenApiPaths);
        nlohmann::json schema = nlohmann::json::parse(kSchemaV1);
        nlohmann::json definitions = schema.at("definitions");
        moveReferences(definitions);
        doc["components"]["schemas"] = definitions;
        return toText(doc);
    }();
    return text;
}

}  // namespace volstyle::protocol

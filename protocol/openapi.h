#pragma once
/// \file openapi.h
/// The API's OpenAPI 3.1 description (SPEC §10), served at /api/v1/openapi.json: the routes of
/// protocol/schema/openapi.json with the JSON Schema of protocol/schema/v1.json as its
/// components (one source for the bodies; the document's schemas are the schema's definitions).

#include <string>

namespace volstyle::protocol {

/// The whole document as JSON text (made once).
const std::string& openApiDocument();

}  // namespace volstyle::protocol

// libFuzzer harness: every JSON request body the server parses (protocol/requests.h), through the
// same steps as a route: parse (size limit, invalid JSON, 1e400), the request type's fromJson, and
// for a refusal the SPEC error body as the server encodes it (invalid UTF-8 once crashed here).
// The first byte picks the request type. Expected refusals are exceptions; anything else — a crash,
// a sanitizer report, an exception of another kind — is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "protocol/error_body.h"
#include "protocol/requests.h"
#include "protocol/validation.h"

using namespace volstyle::protocol;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const std::string body(reinterpret_cast<const char*>(data) + 1, size - 1);
    RequestLimits limits;
    limits.maxImageSide = 256;
    try {
        const nlohmann::json j = parseJsonBody(body, 1 << 20);
        switch (data[0] % 6) {
            case 0: CreateSessionRequest::fromJson(j, limits); break;
            case 1: RenderRequest::fromJson(j, limits); break;
            case 2: AddViewRequest::fromJson(j, limits); break;
            case 3: RevertRequest::fromJson(j); break;
            case 4: SetLightingRequest::fromJson(j).lighting.resolve(nullptr); break;  // "session": no map
            default: SolveRequest::fromJson(j, limits); break;
        }
    } catch (...) {
        const ErrorReport e = describeException(std::current_exception());
        if (e.code == ErrorCode::InternalError) __builtin_trap();  // a refusal must name its cause
        (void)toText(errorBody(e.code, e.message, e.details, "fuzz"));
    }
    return 0;
}

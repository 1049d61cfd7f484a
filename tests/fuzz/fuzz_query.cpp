// libFuzzer harness: request targets as the HTTP library hands them to us — the path (decoded)
// against every route pattern, and the query string into the query types — and the error body a
// refusal or an unknown route answers with (`GET /api/v1/%FF` once crashed the server here).
#include <httplib.h>

#include <cstddef>
#include <cstdint>
#include <regex>
#include <string>

#include "protocol/error_body.h"
#include "protocol/requests.h"
#include "protocol/validation.h"
#include "server/http/routes/route_context.h"

using namespace volstyle;
using namespace volstyle::protocol;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string target(reinterpret_cast<const char*>(data), size);
    const size_t q = target.find('?');
    const std::string path = httplib::detail::decode_url(target.substr(0, q), false);
    static const std::regex routes[] = {std::regex(server::kSessionPath), std::regex(server::kViewPath + "/render\\.(png|exr)"),
                                        std::regex(server::kJobPath + "/events"), std::regex(server::kSessionPath + "/volume\\.vdb")};
    bool routed = false;
    if (path.size() < 4096)  // the library refuses longer URIs (414) before routing
        for (const auto& r : routes) routed |= std::regex_match(path, r);
    httplib::Params params;
    if (q != std::string::npos) httplib::detail::parse_query_text(target.substr(q + 1), params);
    try {
        ViewRenderQuery::fromQuery(params);
        VolumeQuery::fromQuery(params);
        if (!routed) throw ApiError(ErrorCode::NotFound, "no route GET " + path);
    } catch (...) {
        const ErrorReport e = describeException(std::current_exception());
        if (e.code == ErrorCode::InternalError) __builtin_trap();
        (void)toText(errorBody(e.code, e.message, e.details, "fuzz"));
    }
    return 0;
}

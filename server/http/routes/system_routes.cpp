// GET /health, /schema.json, /openapi.json, /scenes, /quarantine.
#include "core/volume/builtin_scenes.h"
#include "protocol/build_version.h"
#include "protocol/openapi.h"
#include "protocol/validation.h"
#include "server/http/routes/route_context.h"

namespace volstyle::server {

void addSystemRoutes(RouteContext& c) {
    c.get(kApi + "/health", [&c](const httplib::Request&, httplib::Response& res) {
        const auto& caps = c.services.sessions.capabilities();
        reply(res, 200, {{"status", "ok"}, {"version", protocol::versionString()}, {"api", protocol::kApiVersion},
                         {"gl_renderer", caps.renderer}, {"gl_version", caps.version}});
    });
    c.get(kApi + "/schema.json", [](const httplib::Request&, httplib::Response& res) {
        res.set_content(protocol::kSchemaV1, "application/schema+json");
    });
    c.get(kApi + "/openapi.json", [](const httplib::Request&, httplib::Response& res) {
        res.set_content(protocol::openApiDocument(), "application/json");
    });
    c.get(kApi + "/scenes", [](const httplib::Request&, httplib::Response& res) {
        nlohmann::json list = nlohmann::json::array();
        for (const auto& s : core::builtinScenes()) list.push_back({{"name", s.name}, {"description", s.description}});
        reply(res, 200, list);
    });
    // Files (or whole sessions) found damaged in the data directory and moved aside, with why.
    c.get(kApi + "/quarantine", [&c](const httplib::Request&, httplib::Response& res) {
        nlohmann::json list = nlohmann::json::array();
        for (const auto& q : c.services.sessions.quarantine())
            list.push_back({{"session", q.session}, {"file", q.file}, {"reason", q.reason}, {"time", q.time}});
        reply(res, 200, list);
    });
}

}  // namespace volstyle::server

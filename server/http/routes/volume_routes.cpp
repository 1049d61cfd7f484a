// A session's volume versions: PUT …/volume (upload a VDB), GET …/volume.vdb[?version=N],
// POST …/revert, …/undo and …/redo, POST …/perturb (bake a perturbation into a new version), POST/DELETE
// …/refraction (a generated glass sphere's refractive index, or none).
#include "protocol/response_json.h"
#include "server/state/session_info.h"
#include "server/http/routes/route_context.h"

namespace volstyle::server {

void addVolumeRoutes(RouteContext& c) {
    putUpload(c, kSessionPath + "/volume", [&c](const httplib::Request& req, httplib::Response& res, const std::string& bytes) {
        auto s = c.services.sessions.find(req.matches[1]);
        c.services.volumes.uploadVdb(*s, bytes);
        reply(res, 200, protocol::sessionToJson(sessionInfo(*s)));
    });
    c.get(kSessionPath + R"(/volume\.vdb)", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        auto query = protocol::VolumeQuery::fromQuery(req.params);
        const std::string name = "volstyle-" + s->id.substr(0, 8) + (query.version ? "-v" + std::to_string(*query.version) : "") + ".vdb";
        VdbDownload vdb = c.services.volumes.downloadVdb(*s, query.version);
        replyDownload(req, res, std::move(vdb.bytes), "application/octet-stream", name, vdb.tag);
    });
    // Volume perturbation baked into a new version (SPEC §9; docs/TRANSLUCENT.md).
    c.post(kSessionPath + "/perturb", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const core::Perturbation p = protocol::perturbationFromJson(c.body(req));
        c.services.volumes.perturb(*s, p);
        reply(res, 200, protocol::sessionToJson(sessionInfo(*s)));
    });
    // A generated refractive index (a glass sphere with noise, issue #16), or none: a new version.
    c.post(kSessionPath + "/refraction", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        c.services.volumes.setRefraction(*s, protocol::glassSphereFromJson(c.body(req)));
        reply(res, 200, protocol::sessionToJson(sessionInfo(*s)));
    });
    c.del(kSessionPath + "/refraction", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        c.services.volumes.setRefraction(*s, std::nullopt);
        reply(res, 200, protocol::sessionToJson(sessionInfo(*s)));
    });
    c.post(kSessionPath + "/revert", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        auto request = protocol::RevertRequest::fromJson(c.body(req));
        c.services.volumes.revert(*s, request.version);
        reply(res, 200, protocol::sessionToJson(sessionInfo(*s)));
    });
    // One step back or forward through what the session showed (each a new version).
    for (auto [route, redo] : {std::pair{"/undo", false}, std::pair{"/redo", true}})
        c.post(kSessionPath + route, [&c, redo](const httplib::Request& req, httplib::Response& res) {
            auto s = c.services.sessions.find(req.matches[1]);
            c.services.volumes.step(*s, redo);
            reply(res, 200, protocol::sessionToJson(sessionInfo(*s)));
        });
}

}  // namespace volstyle::server

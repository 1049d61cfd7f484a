// Sessions, their lighting and renders: POST/GET /sessions, GET/DELETE /sessions/{sid},
// GET/PUT …/lighting, GET …/lighting/environment.{exr,png}, PUT/DELETE …/environment and
// GET …/environment.{exr,png} (the uploaded map), POST …/render.
#include "core/image/image_io.h"
#include "core/scene/environment_lobes.h"
#include "protocol/render_json.h"
#include "protocol/response_json.h"
#include "server/state/session_info.h"
#include "server/http/routes/list_pages.h"
#include "server/http/routes/route_context.h"

namespace volstyle::server {

namespace {

/// The lighting as JSON, naming the session's environment map "session".
nlohmann::json lightingResponse(RouteContext& c, Session& s, const core::Lighting& lighting) {
    return protocol::lightingToJson(lighting, c.services.sessions.environmentMapIfAny(s).get());
}

/// POST …/render: single scattering, or the translucent preview (SPEC §9).
httplib::Server::Handler renderRoute(RouteContext& c) {
    return [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        auto request = protocol::RenderRequest::fromJson(c.body(req), c.limits);
        if (request.mode == protocol::RenderMode::Translucent) {  // SPEC §9
            core::Image medium;
            const core::Image beauty = c.services.volumes.renderTranslucent(*s, request.camera, request.translucent, &medium);
            if (request.format != protocol::ImageFormat::Exr) return replyImage(res, beauty, request.format, request.exposure);
            // As single scattering's: the medium premultiplied, and the picture as a layer.
            res.set_content(core::encodeExrLayers({{"", &medium}, {"beauty", &beauty}}, request.exrHalf),
                            protocol::imageMimeType(request.format));
            return;
        }
        replyImage(res, c.services.volumes.render(*s, request.camera, request.format == protocol::ImageFormat::Exr), request.format,
                   request.exposure, request.exrHalf);
    };
}

/// Sessions: create, list, get, delete, and a render of one.
void addSessionItselfRoutes(RouteContext& c) {
    c.postCreating(kApi + "/sessions", [&c](const httplib::Request& req, httplib::Response& res) {
        auto request = protocol::CreateSessionRequest::fromJson(c.body(req), c.limits);
        const protocol::SessionInfo created = sessionInfo(*c.services.sessions.create(request));
        replyCreated(res, kApi + "/sessions/" + created.id, protocol::sessionToJson(created));
    });
    c.get(kApi + "/sessions", [&c](const httplib::Request& req, httplib::Response& res) {
        const protocol::ListQuery q = protocol::ListQuery::fromQuery(req.params, false);
        std::vector<std::pair<std::string, nlohmann::json>> keyed;
        for (auto& s : c.services.sessions.list()) {
            nlohmann::json j = s.info ? protocol::sessionToJson(*s.info) : nlohmann::json::parse(s.storedJson, nullptr, false);
            if (j.is_discarded()) continue;  // a summary that does not parse (damaged in the store): the session itself still answers
            keyed.emplace_back(j.value("created", "") + "/" + s.id, std::move(j));  // oldest first
        }
        replyPage(res, std::move(keyed), q, kApi + "/sessions");
    });
    c.get(kSessionPath, [&c](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, protocol::sessionToJson(sessionInfo(*c.services.sessions.find(req.matches[1]))));
    });
    c.del(kSessionPath, [&c](const httplib::Request& req, httplib::Response& res) {
        c.services.sessions.remove(req.matches[1]);
        res.status = 204;
    });
    c.post(kSessionPath + "/render", renderRoute(c));
}

/// The lighting, the environment light's lobes as a map, and the session's environment map.
void addLightingRoutes(RouteContext& c) {
    c.get(kSessionPath + "/lighting", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        reply(res, 200, lightingResponse(c, *s, c.services.sessions.lighting(*s)));
    });
    // The environment light's lobes as a lat-long map (docs/LIGHTING.md): EXR (linear) for
    // `background: {"environment": …}` and Blender, PNG (sRGB) for the page's thumbnail.
    c.get(kSessionPath + R"(/lighting/environment\.(exr|png))", [&c](const httplib::Request& req, httplib::Response& res) {
        const core::Lighting l = c.services.sessions.lighting(*c.services.sessions.find(req.matches[1]));
        if (!l.environment.active())
            throw protocol::ApiError(protocol::ErrorCode::NotFound, "the lighting has no environment light (environment.lobes is 0)");
        const bool exr = req.matches[2] == "exr";
        const int width = exr ? 512 : 128;
        replyImage(res, core::lobesToLatLong(l.environment.basis(), core::lobeRadiance(l.environment), width, width / 2),
                   exr ? protocol::ImageFormat::Exr : protocol::ImageFormat::Png);
    });
    c.put(kSessionPath + "/lighting", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        // An empty body is a client mistake, not "no lights" (send {} for that).
        if (req.body.find_first_not_of(" \t\r\n") == std::string::npos)
            throw protocol::ApiError(protocol::ErrorCode::InvalidArgument, "the body is empty; send the lighting object ({} means no light)");
        auto request = protocol::SetLightingRequest::fromJson(c.body(req));
        reply(res, 200, lightingResponse(c, *s, c.services.sessions.setLighting(*s, request.lighting)));
    });
    // The session's environment map: a lat-long EXR/HDR (or PNG/JPEG, linearised) that the
    // lighting names "session" (docs/LIGHTING.md).
    putUpload(c, kSessionPath + "/environment", [&c](const httplib::Request& req, httplib::Response& res, const std::string& bytes) {
        const EnvironmentMapInfo info = c.services.sessions.setEnvironmentMap(*c.services.sessions.find(req.matches[1]), bytes);
        reply(res, 200, protocol::environmentMapToJson(info));
    });
    c.get(kSessionPath + R"(/environment\.(exr|png))", [&c](const httplib::Request& req, httplib::Response& res) {
        auto map = c.services.sessions.environmentMap(*c.services.sessions.find(req.matches[1]));
        replyImage(res, *map, req.matches[2] == "exr" ? protocol::ImageFormat::Exr : protocol::ImageFormat::Png);
    });
    c.del(kSessionPath + "/environment", [&c](const httplib::Request& req, httplib::Response& res) {
        c.services.sessions.removeEnvironmentMap(*c.services.sessions.find(req.matches[1]));
        res.status = 204;
    });
}

}  // namespace

void addSessionRoutes(RouteContext& c) {
    addSessionItselfRoutes(c);
    addLightingRoutes(c);
}

}  // namespace volstyle::server

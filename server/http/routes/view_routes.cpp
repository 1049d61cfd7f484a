// A session's views: POST/GET …/views, GET/DELETE …/views/{vid}, PUT/DELETE …/target, …/weights
// and …/background (the plate), GET …/target.png, …/background.{png,exr} and …/render.{png,exr}.
#include "core/image/image_io.h"
#include "protocol/response_json.h"
#include "server/state/session_info.h"
#include "server/http/routes/route_context.h"

namespace volstyle::server {

void addViewRoutes(RouteContext& c) {
    c.post(kSessionPath + "/views", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        auto request = protocol::AddViewRequest::fromJson(c.body(req), c.limits);
        const protocol::ViewInfo view = viewInfo(c.services.sessions.addView(*s, request.camera, request.frame));
        replyCreated(res, kApi + "/sessions/" + s->id + "/views/" + view.id, protocol::viewToJson(view));
    });
    c.get(kSessionPath + "/views", [&c](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, protocol::viewsToJson(viewInfos(*c.services.sessions.find(req.matches[1]))));
    });
    c.get(kViewPath, [&c](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, protocol::viewToJson(viewInfo(c.services.sessions.view(*c.services.sessions.find(req.matches[1]), req.matches[2]))));
    });
    c.del(kViewPath, [&c](const httplib::Request& req, httplib::Response& res) {
        c.services.sessions.removeView(*c.services.sessions.find(req.matches[1]), req.matches[2]);
        res.status = 204;
    });
    for (ViewImage kind : {ViewImage::Target, ViewImage::Weights, ViewImage::Background}) {
        const std::string part = std::string("/") + viewImageName(kind);
        putUpload(c, kViewPath + part, [&c, kind](const httplib::Request& req, httplib::Response& res, const std::string& bytes) {
            auto s = c.services.sessions.find(req.matches[1]);
            // ?clip_aware=false keeps clipped pixels of an 8/16-bit target at their weight.
            const std::string clip = req.has_param("clip_aware") ? req.get_param_value("clip_aware") : "true";
            if (clip != "true" && clip != "false")
                throw protocol::ApiError(protocol::ErrorCode::InvalidArgument, "?clip_aware must be true or false",
                                         {{"?clip_aware", "must be true or false, got '" + clip.substr(0, 64) + "'"}});
            const bool clipAware = clip == "true";
            reply(res, 200, protocol::viewToJson(viewInfo(c.services.sessions.setViewImage(*s, req.matches[2], kind, bytes, clipAware))));
        });
        c.del(kViewPath + part, [&c, kind](const httplib::Request& req, httplib::Response& res) {
            auto s = c.services.sessions.find(req.matches[1]);
            reply(res, 200, protocol::viewToJson(viewInfo(c.services.sessions.removeViewImage(*s, req.matches[2], kind))));
        });
    }
    // The plate as stored (linear): EXR exactly, PNG sRGB-encoded for the page.
    c.get(kViewPath + R"(/background\.(png|exr))", [&c](const httplib::Request& req, httplib::Response& res) {
        SessionView v = c.services.sessions.view(*c.services.sessions.find(req.matches[1]), req.matches[2]);
        if (!v.background) throw protocol::ApiError(protocol::ErrorCode::NotFound, "view " + v.id + " has no background plate");
        replyImage(res, *v.background, req.matches[3] == "exr" ? protocol::ImageFormat::Exr : protocol::ImageFormat::Png);
    });
    c.get(kViewPath + "/target.png", [&c](const httplib::Request& req, httplib::Response& res) {
        SessionView v = c.services.sessions.view(*c.services.sessions.find(req.matches[1]), req.matches[2]);
        if (!v.target) throw protocol::ApiError(protocol::ErrorCode::NotFound, "view " + v.id + " has no target yet");
        core::SaveOptions save;
        save.writeAlpha = true;  // alpha is the painted weight
        replyDownload(req, res, core::encodeImage(*v.target, "png", save), "image/png", "target-" + v.id + ".png");
    });
    c.get(kViewPath + R"(/render\.(png|exr))", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        auto query = protocol::ViewRenderQuery::fromQuery(req.params);
        const auto format = req.matches[3] == "png" ? protocol::ImageFormat::Png : protocol::ImageFormat::Exr;
        replyImage(res, c.services.volumes.renderView(*s, req.matches[2], format == protocol::ImageFormat::Exr), format, query.exposure,
                   query.exrHalf);
    });
}

}  // namespace volstyle::server

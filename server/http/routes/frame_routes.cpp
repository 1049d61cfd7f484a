// A session's animation (issue #16, docs/ANIMATION.md): PUT/GET/DELETE …/frames/{n}[.vdb],
// GET …/frames, POST …/animate (the key-frame solve, a job), POST …/frames/render (a job
// rendering every frame to PNG).
#include "protocol/response_json.h"
#include "server/state/session_info.h"
#include "server/http/routes/route_context.h"

namespace volstyle::server {
namespace {

const std::string kFramePath = kSessionPath + R"(/frames/([0-9]{1,5}))";

}  // namespace

void addFrameRoutes(RouteContext& c) {
    putUpload(c, kFramePath, [&c](const httplib::Request& req, httplib::Response& res, const std::string& bytes) {
        auto s = c.services.sessions.find(req.matches[1]);
        c.services.volumes.uploadFrame(*s, std::stoi(req.matches[2]), bytes);
        reply(res, 200, protocol::framesToJson(frameInfos(*s)));
    });
    // One VDB holding the whole animation (grids stamped with their frames): every frame at once.
    putUpload(c, kSessionPath + "/frames", [&c](const httplib::Request& req, httplib::Response& res, const std::string& bytes) {
        auto s = c.services.sessions.find(req.matches[1]);
        c.services.volumes.uploadFrames(*s, bytes);
        reply(res, 200, protocol::framesToJson(frameInfos(*s)));
    });
    c.get(kSessionPath + "/frames", [&c](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, protocol::framesToJson(frameInfos(*c.services.sessions.find(req.matches[1]))));
    });
    c.get(kFramePath + R"(\.vdb)", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const int frame = std::stoi(req.matches[2]);
        VdbDownload vdb = c.services.volumes.downloadFrame(*s, frame);
        replyDownload(req, res, std::move(vdb.bytes), "application/octet-stream",
                      "volstyle-" + s->id.substr(0, 8) + "-frame" + std::to_string(frame) + ".vdb", vdb.tag);
    });
    c.del(kFramePath, [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        c.services.volumes.removeFrame(*s, std::stoi(req.matches[2]));
        reply(res, 200, protocol::framesToJson(frameInfos(*s)));
    });
    c.postCreating(kSessionPath + "/animate", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const nlohmann::json body = c.body(req);
        const JobOrigin origin{"animate", protocol::toText(body), nullptr};
        reply(res, 202, {{"job", c.services.volumes.startAnimate(s, protocol::AnimateRequest::fromJson(body), origin)->id}});
    });
    c.postCreating(kSessionPath + "/frames/render", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const nlohmann::json body = c.body(req);
        const JobOrigin origin{"frames-render", protocol::toText(body), nullptr};
        reply(res, 202, {{"job", c.services.volumes.startFramesRender(s, protocol::FramesRenderRequest::fromJson(body, c.limits), origin)->id}});
    });
    // Run again on this replica when the one running them died (the job queue).
    c.services.jobs.addResumer("animate", [&c](const JobOrigin& o, const std::shared_ptr<Session>& s) {
        c.services.volumes.startAnimate(s, protocol::AnimateRequest::fromJson(nlohmann::json::parse(o.request)), o);
    });
    c.services.jobs.addResumer("frames-render", [&c](const JobOrigin& o, const std::shared_ptr<Session>& s) {
        c.services.volumes.startFramesRender(s, protocol::FramesRenderRequest::fromJson(nlohmann::json::parse(o.request), c.limits), o);
    });
}

}  // namespace volstyle::server

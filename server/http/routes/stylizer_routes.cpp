// A session's light-shaft stylizer (SPEC §7 "API"): GET/PUT …/stylizer (the scene),
// GET …/stylizer/occluders, PUT/DELETE …/stylizer/occluders/{name} (mesh files),
// PUT/DELETE …/stylizer/tf and GET …/stylizer/tf.png (the uploaded TF image), GET …/stylizer/transfer_function.png (the
// TF the scene applies, its layers compiled), POST …/stylizer/undo
// and …/redo, POST …/stylizer/pick (a pixel's TF position) and …/constraints (a TF constraint
// clicked into the scene), POST …/stylizer/sequence (a job rendering the camera path), POST …/stylizer/frame
// (a frame or AOV), GET …/stylizer/events (the live stream: SSE `frame` events whose URLs,
// GET …/stylizer/frames/{revision}.jpeg, hold each new revision's frame) and GET …/stylizer/stream
// (the same frames themselves, MJPEG: multipart/x-mixed-replace).
#include <fmt/format.h>

#include <functional>
#include <utility>

#include "core/image/image_io.h"
#include "core/stylize/stylizer.h"
#include "core/stylize/stylizer_files.h"
#include "protocol/error_body.h"
#include "protocol/response_json.h"
#include "protocol/stylize_json.h"
#include "server/http/routes/route_context.h"

namespace volstyle::server {
namespace {

using protocol::ApiError;
using protocol::ErrorCode;

/// How long the live stream waits for a change before checking that its client is still there,
/// and how often it then says so (an SSE comment keeps proxies from closing an idle stream).
constexpr auto kLivePoll = std::chrono::milliseconds(500);
constexpr int kPollsPerKeepAlive = 30;

const std::string kStylizerPath = kSessionPath + "/stylizer";

/// The scene as its JSON, its revision in the ETag (the body round-trips through PUT).
void replyScene(httplib::Response& res, const StylizerSnapshot& s) {
    res.set_header("ETag", fmt::format("\"r{}\"", s.revision));
    reply(res, 200, protocol::stylizerSceneToJson(s.scene, s.meshRefs));
}

std::string frameUrl(const std::string& session, uint64_t revision) {
    return fmt::format("{}/sessions/{}/stylizer/frames/{}.jpeg", kApi, session, revision);
}

std::string sseEvent(const char* event, const nlohmann::json& data) {
    return std::string("event: ") + event + "\ndata: " + protocol::toText(data) + "\n\n";
}

/// How a live stream writes what happens: each new frame, a revision that could not render, the
/// session's end, and a keep-alive while nothing changes.
struct LiveStreamFormat {
    const char* contentType;
    std::function<std::string(const Session&, const LiveFrame&)> frame;
    std::function<std::string(uint64_t revision, const nlohmann::json& error)> failed;
    std::function<std::string(const std::string& reason)> closed;
    std::string keepAlive;
};

/// The live stream: the stylizer's revision now and each later one (a burst of changes renders
/// only the newest: a slow client gets the newest frame next, never a backlog), a failure for a
/// revision that could not render, and the end when the session is deleted.
void streamLive(RouteContext& c, httplib::Response& res, std::shared_ptr<Session> s, const std::string& client, LiveStreamFormat format) {
    c.streams.acquire(client);
    res.set_header("Cache-Control", "no-cache");
    const std::string contentType = format.contentType;
    res.set_chunked_content_provider(
        contentType,
        [&c, s, pipeline = std::shared_ptr<LiveStreamPipeline>(c.services.stylizer.liveStreamPipeline(s)), format = std::move(format),
         sent = uint64_t(0), idle = 0](size_t, httplib::DataSink& sink) mutable {
            std::string message;
            try {
                if (auto f = c.services.stylizer.nextLiveFrame(*pipeline, sent, kLivePoll)) {
                    sent = f->revision;
                    idle = 0;
                    message = format.frame(*s, *f);
                } else if (++idle % kPollsPerKeepAlive == 0) {
                    message = format.keepAlive;
                }
            } catch (...) {
                const protocol::ErrorReport e = protocol::describeException(std::current_exception());
                if (e.code == ErrorCode::NotFound) {  // the session was deleted
                    const std::string end = format.closed(e.message);
                    sink.write(end.data(), end.size());
                    sink.done();
                    return true;
                }
                // The revision that failed (a pipelined render's may be older than the newest,
                // which then renders next); else the newest: wait for the next change.
                sent = pipeline->failedRevision ? std::exchange(pipeline->failedRevision, 0) : c.services.stylizer.stylizer(*s).revision;
                message = format.failed(sent, protocol::errorBody(e.code, e.message, e.details, "")["error"]);
            }
            if (!message.empty() && !sink.write(message.data(), message.size())) return false;  // the client left
            return sink.is_writable();
        },
        [&c, client](bool) { c.streams.release(client); });
}

/// Server-sent events: `frame` with the frame's URL (…/frames/{revision}.jpeg), `failed`, `closed`.
LiveStreamFormat sseFormat() {
    return {"text/event-stream",
            [](const Session& s, const LiveFrame& f) {
                return sseEvent("frame", {{"revision", f.revision}, {"url", frameUrl(s.id, f.revision)}, {"width", f.width},
                                          {"height", f.height}, {"render_ms", f.renderMs}, {"encode_ms", f.encodeMs}});
            },
            [](uint64_t revision, const nlohmann::json& error) { return sseEvent("failed", {{"revision", revision}, {"error", error}}); },
            [](const std::string& reason) { return sseEvent("closed", {{"reason", reason}}); }, ": still here\n\n"};
}

/// The frames themselves in one response (issue #40): a JPEG part per frame (its revision and
/// times in the part's headers), a JSON part for a failed revision or the end, and an empty part
/// as keep-alive (route_context.h's mjpegPart).
LiveStreamFormat mjpegFormat() {
    return {kMjpegContentType,
            [](const Session&, const LiveFrame& f) {
                return mjpegPart("image/jpeg",
                                 fmt::format("X-Revision: {}\r\nX-Width: {}\r\nX-Height: {}\r\nX-Render-Ms: {:.1f}\r\nX-Encode-Ms: {:.1f}\r\n",
                                             f.revision, f.width, f.height, f.renderMs, f.encodeMs),
                                 f.bytes);
            },
            [](uint64_t revision, const nlohmann::json& error) {
                return mjpegPart("application/json", fmt::format("X-Revision: {}\r\n", revision),
                                 protocol::toText({{"event", "failed"}, {"revision", revision}, {"error", error}}));
            },
            [](const std::string& reason) {
                return mjpegPart("application/json", "", protocol::toText({{"event", "closed"}, {"reason", reason}})) +
                       kMjpegEnd;
            },
            mjpegPart("text/plain", "", "")};
}

}  // namespace

namespace {

/// The scene: GET/PUT, undo and redo, picks and clicked constraints, sequences.
void addStylizerSceneRoutes(RouteContext& c) {
    c.get(kStylizerPath, [&c](const httplib::Request& req, httplib::Response& res) {
        replyScene(res, c.services.stylizer.stylizer(*c.services.sessions.find(req.matches[1])));
    });
    c.put(kStylizerPath, [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        if (req.body.find_first_not_of(" \t\r\n") == std::string::npos)  // a mistake, not "the defaults"
            throw ApiError(ErrorCode::InvalidArgument, "the body is empty; send the scene (GET …/stylizer gives the current one)");
        auto request = protocol::stylizerSceneFromJson(c.body(req), "", protocol::SceneSource::Api);
        replyScene(res, c.services.stylizer.setStylizerScene(*s, request));
    });
    for (auto [route, redo] : {std::pair{"/undo", false}, std::pair{"/redo", true}})
        c.post(kStylizerPath + route, [&c, redo](const httplib::Request& req, httplib::Response& res) {
            replyScene(res, c.services.stylizer.undoStylizer(*c.services.sessions.find(req.matches[1]), redo));
        });
    c.post(kStylizerPath + "/pick", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        reply(res, 200, protocol::stylizerPickToJson(c.services.stylizer.pickStylizer(*s, protocol::StylizerPickRequest::fromJson(c.body(req), c.limits, false))));
    });
    c.post(kStylizerPath + "/constraints", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const AddedTfConstraint a = c.services.stylizer.addTfConstraint(*s, protocol::StylizerPickRequest::fromJson(c.body(req), c.limits, true));
        res.set_header("ETag", fmt::format("\"r{}\"", a.revision));
        reply(res, 200, protocol::addedTfConstraintToJson(a));
    });
    c.postCreating(kStylizerPath + "/sequence", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const nlohmann::json body = c.body(req);
        const JobOrigin origin{"sequence", protocol::toText(body), nullptr};
        reply(res, 202, {{"job", c.services.stylizer.startSequence(s, protocol::StylizerSequenceRequest::fromJson(body), origin)->id}});
    });
    // Run again on this replica when the one rendering it died (the job queue).
    c.services.jobs.addResumer("sequence", [&c](const JobOrigin& o, const std::shared_ptr<Session>& s) {
        c.services.stylizer.startSequence(s, protocol::StylizerSequenceRequest::fromJson(nlohmann::json::parse(o.request)), o);
    });
}

/// The uploads: occluder meshes and the transfer-function image.
void addStylizerUploadRoutes(RouteContext& c) {
    c.get(kStylizerPath + "/occluders", [&c](const httplib::Request& req, httplib::Response& res) {
        nlohmann::json list = nlohmann::json::array();
        for (const auto& m : c.services.stylizer.occluderMeshes(*c.services.sessions.find(req.matches[1]))) list.push_back(protocol::occluderMeshToJson(m));
        reply(res, 200, list);
    });
    putUpload(c, kStylizerPath + "/occluders/([^/]+)", [&c](const httplib::Request& req, httplib::Response& res, const std::string& bytes) {
        auto s = c.services.sessions.find(req.matches[1]);
        reply(res, 200, protocol::occluderMeshToJson(c.services.stylizer.putOccluderMesh(*s, req.matches[2], bytes)));
    });
    c.del(kStylizerPath + "/occluders/([^/]+)", [&c](const httplib::Request& req, httplib::Response& res) {
        c.services.stylizer.removeOccluderMesh(*c.services.sessions.find(req.matches[1]), req.matches[2]);
        res.status = 204;
    });
    putUpload(c, kStylizerPath + "/tf", [&c](const httplib::Request& req, httplib::Response& res, const std::string& bytes) {
        const TransferImageInfo t = c.services.stylizer.setTransferImage(*c.services.sessions.find(req.matches[1]), bytes);
        reply(res, 200, protocol::transferImageToJson(t));
    });
    c.get(kStylizerPath + R"(/tf\.png)", [&c](const httplib::Request& req, httplib::Response& res) {
        core::SaveOptions save;
        save.writeAlpha = true;
        replyDownload(req, res, core::encodeImage(c.services.stylizer.transferImage(*c.services.sessions.find(req.matches[1])), "png", save),
                      "image/png", "tf.png");
    });
    c.get(kStylizerPath + R"(/transfer_function\.png)", [&c](const httplib::Request& req, httplib::Response& res) {
        core::SaveOptions save;
        save.writeAlpha = true;
        save.data = true;  // the TF's values as they are (it multiplies linear radiance)
        replyDownload(req, res,
                      core::encodeImage(c.services.stylizer.compiledTransferFunction(*c.services.sessions.find(req.matches[1])), "png", save),
                      "image/png", "transfer_function.png");
    });
    c.del(kStylizerPath + "/tf", [&c](const httplib::Request& req, httplib::Response& res) {
        c.services.stylizer.removeTransferImage(*c.services.sessions.find(req.matches[1]));
        res.status = 204;
    });
}

/// Frames: one on request, and the live stream's.
void addStylizerFrameRoutes(RouteContext& c) {
    c.post(kStylizerPath + "/frame", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const auto request = protocol::StylizerFrameRequest::fromJson(c.body(req), c.limits);
        const core::StylizedFrame f = c.services.stylizer.stylize(*s, request);
        res.set_header("X-Render-Ms", fmt::format("{:.1f}", f.totalMs));
        const core::SaveOptions save =
            core::stylizerSaveOptions(request.output, request.format == protocol::ImageFormat::Exr ? 0 : request.exposure);
        res.set_content(core::encodeImage(f.output(request.output), protocol::imageFormatName(request.format), save),
                        protocol::imageMimeType(request.format));
    });
    c.get(kStylizerPath + "/events", [&c](const httplib::Request& req, httplib::Response& res) {
        streamLive(c, res, c.services.sessions.find(req.matches[1]), req.remote_addr, sseFormat());
    });
    c.get(kStylizerPath + "/stream", [&c](const httplib::Request& req, httplib::Response& res) {
        streamLive(c, res, c.services.sessions.find(req.matches[1]), req.remote_addr, mjpegFormat());
    });
    c.get(kStylizerPath + R"(/frames/([0-9]+)\.jpeg)", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const uint64_t revision = std::stoull(req.matches[2].str().substr(0, 19));
        auto f = c.services.stylizer.liveFrame(*s, revision);
        if (!f) throw ApiError(ErrorCode::NotFound, "the live stream holds no frame of revision " + std::to_string(revision) +
                                                        " (a newer one replaced it; follow …/stylizer/events)");
        res.set_header("Cache-Control", "private, max-age=3600");  // a revision's frame never changes
        res.set_content(f->bytes, "image/jpeg");
    });
}

}  // namespace

void addStylizerRoutes(RouteContext& c) {
    addStylizerSceneRoutes(c);
    addStylizerUploadRoutes(c);
    addStylizerFrameRoutes(c);
}

}  // namespace volstyle::server

#include "server/http_server.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <ctime>

#include "core/errors.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/volume/builtin_scenes.h"
#include "protocol/error_body.h"
#include "protocol/render_json.h"
#include "server/gl_worker.h"
#include "server/session_store.h"

namespace volstyle::server {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

/// An error with its own HTTP code (limits, auth, unknown routes).
struct ApiError : std::runtime_error {
    std::string code;
    std::vector<protocol::FieldError> details;
    ApiError(std::string c, const std::string& message, std::vector<protocol::FieldError> d = {})
        : std::runtime_error(message), code(std::move(c)), details(std::move(d)) {}
};

bool isLoopback(const std::string& host) { return host == "127.0.0.1" || host == "localhost" || host == "::1"; }

/// Compares in time independent of where the strings differ.
bool constantTimeEquals(const std::string& a, const std::string& b) {
    unsigned char diff = a.size() == b.size() ? 0 : 1;
    for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i % std::max<size_t>(b.size(), 1)]);
    return diff == 0;
}

std::string isoNow() {
    std::time_t t = std::time(nullptr);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
    return buf;
}

json vec(const Vec3d& v) { return json::array({v.x, v.y, v.z}); }

thread_local Clock::time_point t_requestStart;
thread_local std::string t_requestId;

}  // namespace

struct HttpServer::Impl {
    ServerOptions opt;
    httplib::Server http;
    std::unique_ptr<GlWorker> gl;
    SessionStore sessions;
    std::atomic<uint64_t> requestCounter{0};

    explicit Impl(ServerOptions o) : opt(std::move(o)), sessions(opt.maxSessions) {}

    json parseBody(const httplib::Request& req) {
        if (req.body.size() > opt.maxJsonBytes)
            throw ApiError("too_large", "the JSON body is " + std::to_string(req.body.size()) +
                                            " bytes; the limit is " + std::to_string(opt.maxJsonBytes));
        if (req.body.empty()) return json::object();
        try {
            return json::parse(req.body);
        } catch (const json::parse_error& e) {
            throw ApiError("invalid_json", std::string("the body is not valid JSON: ") + e.what());
        }
    }

    std::shared_ptr<Session> session(const std::string& id) {
        auto s = sessions.find(id);
        if (!s) throw ApiError("not_found", "no session '" + id + "'");
        return s;
    }

    json sessionJson(Session& s) {
        std::lock_guard lock(s.mutex);
        const core::Volume& v = s.volume;
        auto [lo, hi] = v.worldBounds();
        json grids = json::array({"extinction"});
        if (v.hasAlbedo()) grids.push_back("albedo");
        if (v.hasEmission()) grids.push_back("emission");
        Vec3d vs = v.voxelSize();
        return {{"id", s.id},
                {"created", s.created},
                {"scene", s.scene},
                {"volume", {{"dims", {v.dims().x, v.dims().y, v.dims().z}}, {"bbox", {vec(lo), vec(hi)}},
                            {"voxel_size", vec(vs)}, {"grids", grids}, {"version", s.version}}},
                {"lighting", protocol::lightingToJson(s.lighting)},
                {"views", json::array()},
                {"jobs", json::array()}};
    }

    void reply(httplib::Response& res, int status, const json& body) {
        res.status = status;
        res.set_content(body.dump(), "application/json");
    }

    void routes();
};

HttpServer::HttpServer(ServerOptions options) : m(std::make_unique<Impl>(std::move(options))) {
    if (!isLoopback(m->opt.host) && m->opt.token.empty())
        throw InvalidArgument("serve: binding " + m->opt.host +
                              " exposes the API beyond this machine; give --token (or VOLSTYLE_TOKEN)");
    m->gl = std::make_unique<GlWorker>();
    m->routes();
}

HttpServer::~HttpServer() {
    stop();
    // GPU copies of volumes die on the GL thread.
    for (auto& s : m->sessions.all())
        if (s->gpu) m->gl->run([gpu = std::move(s->gpu)](core::Renderer&) mutable { gpu.reset(); });
}

int HttpServer::bind() {
    if (m->opt.port == 0) return m->http.bind_to_any_port(m->opt.host);
    if (!m->http.bind_to_port(m->opt.host, m->opt.port))
        throw IoError("serve: cannot listen on " + m->opt.host + ":" + std::to_string(m->opt.port) + " (in use?)");
    return m->opt.port;
}

void HttpServer::listen() { m->http.listen_after_bind(); }
void HttpServer::stop() { m->http.stop(); }

void HttpServer::Impl::routes() {
    http.set_payload_max_length(size_t(512) << 20);

    // Request ids, timing, and the bearer token on /api when one is set.
    http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
        t_requestStart = Clock::now();
        t_requestId = fmt::format("{:08x}", ++requestCounter);
        res.set_header("X-Request-Id", t_requestId);
        if (!opt.token.empty() && req.path.rfind("/api/", 0) == 0) {
            const std::string auth = req.get_header_value("Authorization");
            if (!constantTimeEquals(auth, "Bearer " + opt.token)) {
                reply(res, 401, protocol::errorBody("unauthorized", "send 'Authorization: Bearer <token>'", {}, t_requestId));
                return httplib::Server::HandlerResponse::Handled;
            }
        }
        return httplib::Server::HandlerResponse::Unhandled;
    });
    http.set_logger([](const httplib::Request& req, const httplib::Response& res) {
        double ms = std::chrono::duration<double, std::milli>(Clock::now() - t_requestStart).count();
        spdlog::info("{} {} {} {:.1f} ms id={}", req.method, req.path, res.status, ms, t_requestId);
    });
    // One exception handler for every route (cpp-httplib's advice): the SPEC's error body.
    http.set_exception_handler([this](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        std::string code = "internal_error", message = "unexpected error";
        std::vector<protocol::FieldError> details;
        try {
            std::rethrow_exception(ep);
        } catch (const ApiError& e) {
            code = e.code, message = e.what(), details = e.details;
        } catch (const protocol::ValidationError& e) {
            code = e.code(), message = e.what(), details = e.details();
        } catch (const Error& e) {
            code = e.code(), message = e.what();
        } catch (const std::exception& e) {
            message = e.what();
        } catch (...) {
        }
        const int status = protocol::httpStatusFor(code);
        if (status >= 500) spdlog::error("request {}: {}: {}", t_requestId, code, message);
        reply(res, status, protocol::errorBody(code, message, details, t_requestId));
    });
    http.set_error_handler([this](const httplib::Request& req, httplib::Response& res) {
        if (res.status == 404 && res.body.empty())
            reply(res, 404, protocol::errorBody("not_found", "no route " + req.method + " " + req.path, {}, t_requestId));
    });

    const std::string api = "/api/v1";
    http.Get(api + "/health", [this](const httplib::Request&, httplib::Response& res) {
        const auto& caps = gl->capabilities();
        reply(res, 200, {{"status", "ok"}, {"version", "0.1.0"}, {"api", protocol::kApiVersion},
                         {"gl_renderer", caps.renderer}, {"gl_version", caps.version}});
    });
    http.Get(api + "/scenes", [this](const httplib::Request&, httplib::Response& res) {
        json list = json::array();
        for (const auto& s : core::builtinScenes()) list.push_back({{"name", s.name}, {"description", s.description}});
        reply(res, 200, list);
    });
    http.Post(api + "/sessions", [this](const httplib::Request& req, httplib::Response& res) {
        json body = parseBody(req);
        protocol::JsonReader r;
        std::string scene = "builtin:cloud";
        int resolution = 128;
        if (r.object(body, "", {"scene", "resolution"})) {
            if (body.contains("scene")) scene = r.string(body["scene"], "/scene").value_or(scene);
            if (body.contains("resolution")) resolution = r.integer(body["resolution"], "/resolution").value_or(resolution);
            if (scene.rfind("builtin:", 0) != 0)
                r.fail("/scene", "must be builtin:NAME (upload a VDB with PUT …/volume instead)");
            if (resolution < 8 || resolution > core::kMaxSceneResolution)
                r.fail("/resolution", "must be in [8, " + std::to_string(core::kMaxSceneResolution) + "]");
        }
        r.throwIfErrors();
        auto s = std::make_shared<Session>();
        s->created = isoNow();
        s->scene = scene;
        s->volume = core::makeBuiltinScene(scene.substr(8), resolution);  // InvalidArgument lists the scenes
        s->lighting = core::defaultLighting();
        sessions.add(s);
        reply(res, 201, sessionJson(*s));
    });
    http.Get(api + "/sessions", [this](const httplib::Request&, httplib::Response& res) {
        json list = json::array();
        for (auto& s : sessions.all()) list.push_back(sessionJson(*s));
        reply(res, 200, list);
    });
    http.Get(api + R"(/sessions/([0-9a-f]+))", [this](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, sessionJson(*session(req.matches[1])));
    });
    http.Delete(api + R"(/sessions/([0-9a-f]+))", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = sessions.remove(req.matches[1]);
        if (!s) throw ApiError("not_found", "no session '" + std::string(req.matches[1]) + "'");
        std::lock_guard lock(s->mutex);
        if (s->gpu) gl->run([gpu = std::move(s->gpu)](core::Renderer&) mutable { gpu.reset(); });
        res.status = 204;
    });
    http.Get(api + R"(/sessions/([0-9a-f]+)/lighting)", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        std::lock_guard lock(s->mutex);
        reply(res, 200, protocol::lightingToJson(s->lighting));
    });
    http.Put(api + R"(/sessions/([0-9a-f]+)/lighting)", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        core::Lighting l = protocol::lightingFromJson(parseBody(req)).lighting;
        std::lock_guard lock(s->mutex);
        s->lighting = l;
        reply(res, 200, protocol::lightingToJson(s->lighting));
    });
    http.Post(api + R"(/sessions/([0-9a-f]+)/render)", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        json body = parseBody(req);
        protocol::JsonReader r;
        core::Camera camera;
        std::string format = "png";
        double exposure = 0;
        if (r.object(body, "", {"camera", "format", "exposure", "mode"})) {
            if (!body.contains("camera")) r.fail("/camera", "is required");
            else try {
                camera = protocol::cameraFromJson(body["camera"], "/camera");
            } catch (const protocol::ValidationError& e) {
                for (const auto& d : e.details()) r.fail(d.path, d.message);
            }
            if (body.contains("format")) format = r.string(body["format"], "/format").value_or(format);
            if (format != "png" && format != "exr") r.fail("/format", "must be 'png' or 'exr'");
            if (body.contains("exposure")) exposure = r.number(body["exposure"], "/exposure").value_or(0);
            if (body.contains("mode") && r.string(body["mode"], "/mode").value_or("") != "single_scattering")
                r.fail("/mode", "must be 'single_scattering'");
            if (camera.width > opt.maxImageSide || camera.height > opt.maxImageSide)
                r.fail("/camera", "images are limited to " + std::to_string(opt.maxImageSide) + " pixels a side");
        }
        r.throwIfErrors();
        std::lock_guard lock(s->mutex);
        core::Image image = gl->run([&](core::Renderer& renderer) {
            if (!s->gpu) s->gpu = std::make_shared<core::GpuVolume>(s->volume);
            return renderer.render(*s->gpu, camera, s->lighting);
        });
        core::SaveOptions save;
        save.exposure = format == "png" ? exposure : 0;
        res.set_content(core::encodeImage(image, format, save), format == "png" ? "image/png" : "image/x-exr");
    });
    if (!opt.webDir.empty()) http.set_mount_point("/", opt.webDir);  // httplib refuses '..' paths
}

}  // namespace volstyle::server

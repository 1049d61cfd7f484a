#include "server/http_server.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/volume/builtin_scenes.h"
#include "protocol/error_body.h"
#include "protocol/render_json.h"
#include "core/solve/solver.h"
#include "core/volume/vdb_io.h"
#include "protocol/solve_json.h"
#include "server/gl_worker.h"
#include "server/job_store.h"
#include "server/persistence.h"
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
    JobStore jobs;
    std::unique_ptr<Persistence> persist;  ///< null: in memory only
    static constexpr size_t kMaxQueuedJobs = 4;

    // Durability hooks: each runs before the answer is sent.
    void saved(const Session& s) {
        if (persist) persist->saveSession(s);
    }
    void saved(const Job& j) {
        if (persist) persist->saveJob(j);
    }
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
                {"views", viewsJson(s)},
                {"jobs", s.jobs}};
    }

    static json viewJson(const SessionView& v) {
        return {{"id", v.id}, {"camera", protocol::cameraToJson(v.camera)}, {"has_target", v.target.has_value()},
                {"has_weights", v.weights.has_value()}};
    }
    static json viewsJson(const Session& s) {
        json list = json::array();
        for (const auto& v : s.views) list.push_back(viewJson(v));
        return list;
    }
    static SessionView& view(Session& s, const std::string& id) {
        for (auto& v : s.views)
            if (v.id == id) return v;
        throw ApiError("not_found", "no view '" + id + "' in session '" + s.id + "'");
    }

    void checkUploadSize(const std::string& bytes, const std::string& what) {
        if (bytes.size() > opt.maxUploadBytes)
            throw ApiError("too_large", what + " is " + std::to_string(bytes.size()) + " bytes; the upload limit is " +
                                            std::to_string(opt.maxUploadBytes) + " bytes");
    }

    /// Decodes an uploaded image; anything undecodable is 422.
    core::Image decodeImage(const std::string& bytes, const std::string& what) {
        checkUploadSize(bytes, what);
        try {
            return core::loadImageFromMemory(bytes.data(), bytes.size(), what, opt.maxImageSide).image;
        } catch (const Error& e) {
            throw ApiError("unsupported_media", e.what());
        }
    }

    /// Renders `volume` (uploaded for this call) or the session's own GPU copy, on the GL thread.
    std::string renderImage(Session& s, const core::Volume* volume, const core::Camera& camera, const std::string& format,
                            double exposure) {
        core::Lighting lighting;
        std::shared_ptr<core::GpuVolume> gpu;
        {
            std::lock_guard lock(s.mutex);
            lighting = s.lighting;
        }
        core::Image image = gl->run([&](core::GpuDevice& device) {
            core::Renderer renderer(device);
            if (volume) return renderer.render(*std::make_unique<core::GpuVolume>(*volume), camera, lighting);
            std::lock_guard lock(s.mutex);
            if (!s.gpu) s.gpu = std::make_shared<core::GpuVolume>(s.volume);
            return renderer.render(*s.gpu, camera, lighting);
        });
        core::SaveOptions save;
        save.exposure = format == "png" ? exposure : 0;
        return core::encodeImage(image, format, save);
    }

    /// Makes `volume` the session's newest version, on disk before this returns. Call with the
    /// session's mutex held; returns the stale GPU copy (release it after unlocking).
    std::shared_ptr<core::GpuVolume> commitVersion(Session& s, core::Volume volume) {
        s.volume = std::move(volume);
        s.version = s.versions.rbegin()->first + 1;
        s.versions[s.version] = s.volume;
        saved(s);
        return std::move(s.gpu);
    }

    /// Frees a GPU volume on the GL thread. Call without holding a session's mutex: the GL thread
    /// may be finishing a solve that needs it.
    void release(std::shared_ptr<core::GpuVolume> gpu) {
        if (gpu) gl->run([gpu = std::move(gpu)](core::GpuDevice&) mutable { gpu.reset(); });
    }

    void runSolve(const std::shared_ptr<Job>& job, const std::shared_ptr<Session>& s, core::SolveOptions options,
                  core::GpuDevice& device);

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
    if (!m->opt.dataDir.empty()) {
        m->persist = std::make_unique<Persistence>(m->opt.dataDir);
        for (auto& s : m->persist->loadSessions()) m->sessions.restore(s);
        for (auto& j : m->persist->loadJobs()) m->jobs.restore(j);
        spdlog::info("restored {} session(s) from '{}'", m->sessions.size(), m->opt.dataDir);
    }
    m->routes();
}

HttpServer::~HttpServer() {
    stop();
    // GPU copies of volumes die on the GL thread.
    for (auto& s : m->sessions.all()) m->release(std::move(s->gpu));
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
    http.set_payload_max_length(opt.maxUploadBytes + (1 << 20));

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
    http.Get(api + "/schema.json", [](const httplib::Request&, httplib::Response& res) {
        res.set_content(protocol::kSchemaV1, "application/schema+json");
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
        if (sessions.size() >= opt.maxSessions)
            throw ApiError("too_many_sessions", "the server holds its limit of " + std::to_string(opt.maxSessions) +
                                                    " sessions; delete one first");
        auto s = std::make_shared<Session>();
        s->created = isoNow();
        s->scene = scene;
        s->volume = core::makeBuiltinScene(scene.substr(8), resolution);  // InvalidArgument lists the scenes
        s->lighting = core::defaultLighting();
        s->versions[1] = s->volume;
        sessions.add(s);
        saved(*s);
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
        if (persist) persist->removeSession(s->id);
        std::shared_ptr<core::GpuVolume> gpu;
        {
            std::lock_guard lock(s->mutex);
            gpu = std::move(s->gpu);
        }
        release(std::move(gpu));
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
        saved(*s);
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
        // Never hold the session's mutex while waiting for the GL thread (renderImage locks inside).
        const std::string bytes = renderImage(*s, nullptr, camera, format, exposure);
        res.set_content(bytes, format == "png" ? "image/png" : "image/x-exr");
    });
    const std::string sid = R"(/sessions/([0-9a-f]+))", vid = R"(/views/(v[0-9]+))", jid = R"(/jobs/([0-9a-f]+))";
    http.Post(api + sid + "/views", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        json body = parseBody(req);
        protocol::JsonReader r;
        core::Camera camera;
        if (r.object(body, "", {"camera"})) {
            if (!body.contains("camera")) r.fail("/camera", "is required");
            else try {
                camera = protocol::cameraFromJson(body["camera"], "/camera");
            } catch (const protocol::ValidationError& e) {
                for (const auto& d : e.details()) r.fail(d.path, d.message);
            }
            if (camera.width > opt.maxImageSide || camera.height > opt.maxImageSide)
                r.fail("/camera", "images are limited to " + std::to_string(opt.maxImageSide) + " pixels a side");
        }
        r.throwIfErrors();
        std::lock_guard lock(s->mutex);
        s->views.push_back({"v" + std::to_string(s->nextView++), camera, std::nullopt, std::nullopt});
        saved(*s);
        reply(res, 201, viewJson(s->views.back()));
    });
    http.Get(api + sid + "/views", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        std::lock_guard lock(s->mutex);
        reply(res, 200, viewsJson(*s));
    });
    http.Get(api + sid + vid, [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        std::lock_guard lock(s->mutex);
        reply(res, 200, viewJson(view(*s, req.matches[2])));
    });
    http.Delete(api + sid + vid, [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        std::lock_guard lock(s->mutex);
        view(*s, req.matches[2]);  // 404 if absent
        std::erase_if(s->views, [&](const SessionView& v) { return v.id == req.matches[2]; });
        if (persist) persist->removeView(s->id, req.matches[2]);
        saved(*s);
        res.status = 204;
    });
    for (const char* part : {"target", "weights"}) {
        const bool isTarget = std::string(part) == "target";
        http.Put(api + sid + vid + "/" + part, [this, isTarget](const httplib::Request& req, httplib::Response& res) {
            auto s = session(req.matches[1]);
            core::Image image = decodeImage(req.body, isTarget ? "the target" : "the weight image");
            std::lock_guard lock(s->mutex);
            SessionView& v = view(*s, req.matches[2]);
            if (image.width != v.camera.width || image.height != v.camera.height)
                throw ApiError("invalid_argument", "the image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                                       " but view " + v.id + " renders " + std::to_string(v.camera.width) + "x" +
                                                       std::to_string(v.camera.height));
            if (persist) persist->saveViewImage(s->id, v.id, isTarget ? "target" : "weights", image);
            (isTarget ? v.target : v.weights) = std::move(image);
            saved(*s);
            reply(res, 200, viewJson(v));
        });
    }
    http.Get(api + sid + vid + "/target.png", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        std::lock_guard lock(s->mutex);
        SessionView& v = view(*s, req.matches[2]);
        if (!v.target) throw ApiError("not_found", "view " + v.id + " has no target yet");
        core::SaveOptions save;
        save.writeAlpha = true;
        res.set_content(core::encodeImage(*v.target, "png", save), "image/png");
    });
    http.Get(api + sid + vid + R"(/render\.(png|exr))", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        core::Camera camera;
        {
            std::lock_guard lock(s->mutex);
            camera = view(*s, req.matches[2]).camera;
        }
        const std::string format = req.matches[3];
        double exposure = req.has_param("exposure") ? std::atof(req.get_param_value("exposure").c_str()) : 0;
        res.set_content(renderImage(*s, nullptr, camera, format, exposure), format == "png" ? "image/png" : "image/x-exr");
    });
    http.Post(api + sid + "/solve", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        core::SolveOptions options = protocol::solveOptionsFromJson(parseBody(req));
        if (jobs.pending(s->id) >= kMaxQueuedJobs)
            throw ApiError("too_many_jobs", "session '" + s->id + "' already has " + std::to_string(kMaxQueuedJobs) +
                                                " queued jobs (the limit); wait or cancel one");
        {
            std::lock_guard lock(s->mutex);
            bool anyTarget = false;
            for (const auto& v : s->views) anyTarget |= v.target.has_value();
            if (!anyTarget) throw ApiError("invalid_argument", "no view has a target; PUT …/views/{vid}/target first");
        }
        auto job = jobs.add(s->id);
        saved(*job);
        {
            std::lock_guard lock(s->mutex);
            s->jobs.push_back(job->id);
            saved(*s);
        }
        spdlog::info("job {} queued (session {})", job->id, s->id);
        gl->submit([this, job, s, options](core::GpuDevice& device) { runSolve(job, s, options, device); });
        reply(res, 202, {{"job", job->id}});
    });
    http.Get(api + jid, [this](const httplib::Request& req, httplib::Response& res) {
        auto job = jobs.find(req.matches[1]);
        if (!job) throw ApiError("not_found", "no job '" + std::string(req.matches[1]) + "'");
        reply(res, 200, job->toJson());
    });
    http.Delete(api + jid, [this](const httplib::Request& req, httplib::Response& res) {
        auto job = jobs.find(req.matches[1]);
        if (!job) throw ApiError("not_found", "no job '" + std::string(req.matches[1]) + "'");
        job->cancel = true;
        reply(res, 202, job->toJson());
    });
    http.Get(api + jid + "/events", [this](const httplib::Request& req, httplib::Response& res) {
        auto job = jobs.find(req.matches[1]);
        if (!job) throw ApiError("not_found", "no job '" + std::string(req.matches[1]) + "'");
        res.set_header("Cache-Control", "no-cache");
        // The stream ends after the final event (done, failed or cancelled) has been written; the
        // job's state flips before that event is queued, so the events decide, not the state.
        res.set_chunked_content_provider("text/event-stream", [job, sent = size_t(0)](size_t, httplib::DataSink& sink) mutable {
            std::unique_lock lock(job->mutex);
            job->changed.wait_for(lock, std::chrono::milliseconds(500), [&] { return job->events.size() > sent; });
            bool final = false;
            while (sent < job->events.size()) {
                const auto& [event, data] = job->events[sent++];
                final = event == "done" || event == "failed" || event == "cancelled";
                std::string message = "event: " + event + "\ndata: " + data.dump() + "\n\n";
                lock.unlock();
                if (!sink.write(message.data(), message.size())) return false;  // the client left
                lock.lock();
            }
            if (final) {
                lock.unlock();
                sink.done();
            }
            return true;
        });
    });
    http.Get(api + jid + "/preview/" + R"((v[0-9]+)\.png)", [this](const httplib::Request& req, httplib::Response& res) {
        auto job = jobs.find(req.matches[1]);
        if (!job) throw ApiError("not_found", "no job '" + std::string(req.matches[1]) + "'");
        auto s = session(job->session);
        std::optional<core::Volume> preview;
        {
            std::lock_guard lock(job->mutex);
            preview = job->preview;
        }
        core::Camera camera;
        {
            std::lock_guard lock(s->mutex);
            camera = view(*s, req.matches[2]).camera;
        }
        res.set_content(renderImage(*s, preview ? &*preview : nullptr, camera, "png", 0), "image/png");
    });
    http.Get(api + sid + R"(/volume\.vdb)", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        core::Volume v;
        {
            std::lock_guard lock(s->mutex);
            int version = req.has_param("version") ? std::atoi(req.get_param_value("version").c_str()) : s->version;
            auto it = s->versions.find(version);
            if (it == s->versions.end()) throw ApiError("not_found", "session '" + s->id + "' has no version " + std::to_string(version));
            v = it->second;
        }
        const std::string tmp = (std::filesystem::temp_directory_path() / ("volstyle-" + SessionStore::newId() + ".vdb")).string();
        core::saveVdb(tmp, v);
        std::ifstream f(tmp, std::ios::binary);
        std::stringstream bytes;
        bytes << f.rdbuf();
        std::filesystem::remove(tmp);
        res.set_content(bytes.str(), "application/octet-stream");
    });
    http.Put(api + sid + "/volume", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        checkUploadSize(req.body, "the VDB");
        const std::string tmp = (std::filesystem::temp_directory_path() / ("volstyle-" + SessionStore::newId() + ".vdb")).string();
        std::ofstream(tmp, std::ios::binary).write(req.body.data(), std::streamsize(req.body.size()));
        core::Volume v;
        try {
            v = core::loadVdb(tmp, opt.volumeLimits);
        } catch (const Error& e) {
            std::filesystem::remove(tmp);
            std::string msg = e.what();
            for (size_t pos; (pos = msg.find(tmp)) != std::string::npos;) msg.replace(pos, tmp.size(), "the upload");
            throw ApiError(msg.find("over the limit") != std::string::npos ? "too_large" : "unsupported_media", msg);
        }
        std::filesystem::remove(tmp);
        std::shared_ptr<core::GpuVolume> stale;
        {
            std::lock_guard lock(s->mutex);
            stale = commitVersion(*s, std::move(v));
        }
        release(std::move(stale));
        reply(res, 200, sessionJson(*s));
    });
    http.Post(api + sid + "/revert", [this](const httplib::Request& req, httplib::Response& res) {
        auto s = session(req.matches[1]);
        json body = parseBody(req);
        protocol::JsonReader r;
        int version = 0;
        if (r.object(body, "", {"version"})) {
            if (!body.contains("version")) r.fail("/version", "is required");
            else version = r.integer(body["version"], "/version").value_or(0);
        }
        r.throwIfErrors();
        std::shared_ptr<core::GpuVolume> stale;
        {
            std::lock_guard lock(s->mutex);
            auto it = s->versions.find(version);
            if (it == s->versions.end()) throw ApiError("not_found", "session '" + s->id + "' has no version " + std::to_string(version));
            // Undo is a new version with the old content: nothing is lost.
            stale = commitVersion(*s, it->second);
        }
        release(std::move(stale));
        reply(res, 200, sessionJson(*s));
    });
    if (!opt.webDir.empty()) http.set_mount_point("/", opt.webDir);  // httplib refuses '..' paths
}

void HttpServer::Impl::runSolve(const std::shared_ptr<Job>& job, const std::shared_ptr<Session>& s,
                                core::SolveOptions options, core::GpuDevice& device) {
    if (job->cancel) {
        std::lock_guard lock(job->mutex);
        job->state = "cancelled";
        job->error = protocol::errorBody("cancelled", "cancelled before it started", {}, "")["error"];
    } else {
        {
            std::lock_guard lock(job->mutex);
            job->state = "running";
        }
        saved(*job);
        spdlog::info("job {} running", job->id);
        try {
            // Snapshot the session: the solve works on copies; the session changes only on success.
            core::Volume volume;
            core::Lighting lighting;
            std::vector<core::SolveView> views;
            std::vector<std::string> viewIds;
            {
                std::lock_guard lock(s->mutex);
                volume = s->volume;
                lighting = s->lighting;
                for (const auto& v : s->views) {
                    viewIds.push_back(v.id);
                    views.push_back({v.id, v.camera, v.target.value_or(core::Image()), v.weights});
                }
            }
            core::Solver solver(device, volume, lighting, std::move(views), options);
            auto lastPreview = Clock::now() - std::chrono::hours(1);
            core::SolveResult result = solver.run([&](const core::SolveProgress& p) {
                json progress = protocol::solveProgressToJson(p);
                {
                    std::lock_guard lock(job->mutex);
                    job->progress = progress;
                }
                job->emit("progress", progress);
                // Previews at most once a second: the latest iterate, rendered on request.
                if (Clock::now() - lastPreview >= std::chrono::seconds(1)) {
                    lastPreview = Clock::now();
                    core::Volume current = solver.currentVolume();
                    json urls = json::object();
                    for (const auto& id : viewIds) urls[id] = "/api/v1/jobs/" + job->id + "/preview/" + id + ".png";
                    {
                        std::lock_guard lock(job->mutex);
                        job->preview = std::move(current);
                    }
                    job->emit("preview", {{"iteration", p.iteration}, {"urls", urls}});
                }
                gl->runShortTasks(device);  // renders waiting for the GL thread run between iterations
            }, &job->cancel);
            int version = 0;
            {
                std::lock_guard lock(s->mutex);
                commitVersion(*s, std::move(result.volume));  // on disk before the job reads done
                version = s->version;
                s->gpu = std::make_shared<core::GpuVolume>(s->volume);  // on the GL thread, which frees the old one
            }
            std::lock_guard lock(job->mutex);
            job->state = "done";
            job->result = {{"version", version}, {"report", protocol::solveReportToJson(result.report)}};
        } catch (const Cancelled& e) {
            std::lock_guard lock(job->mutex);
            job->state = "cancelled";
            job->error = protocol::errorBody("cancelled", e.what(), {}, "")["error"];
        } catch (const protocol::ValidationError& e) {
            std::lock_guard lock(job->mutex);
            job->state = "failed";
            job->error = protocol::errorBody(e.code(), e.what(), e.details(), "")["error"];
        } catch (const Error& e) {
            std::lock_guard lock(job->mutex);
            job->state = "failed";
            job->error = protocol::errorBody(e.code(), e.what(), {}, "")["error"];
        } catch (const std::exception& e) {
            std::lock_guard lock(job->mutex);
            job->state = "failed";
            job->error = protocol::errorBody("internal_error", e.what(), {}, "")["error"];
        }
    }
    std::string state;
    {
        std::lock_guard lock(job->mutex);
        state = job->state;
    }
    spdlog::info("job {} {}", job->id, state);
    try {
        saved(*job);
    } catch (const std::exception& e) {
        spdlog::error("job {}: cannot record its end: {}", job->id, e.what());
    }
    job->emit(state, job->toJson());
}

}  // namespace volstyle::server

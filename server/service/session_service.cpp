#include "server/service/session_service.h"

#include "core/solve/solve_cache.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <ctime>
#include <filesystem>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/translucent/translucent_renderer.h"
#include "core/stylize/stylizer.h"
#include "core/volume/builtin_scenes.h"
#include "server/runtime/gl_worker.h"
#include "server/runtime/mesh_reader.h"

namespace volstyle::server {
namespace {

using protocol::ApiError;
using protocol::ErrorCode;

SessionView& findView(Session& s, const std::string& id) {
    for (auto& v : s.views)
        if (v.id == id) return v;
    throw ApiError(ErrorCode::NotFound, "no view '" + id + "' in session '" + s.id + "'");
}

}  // namespace

SessionService::SessionService(ServiceLimits limits, const std::string& dataDir, std::unique_ptr<GlExecutor> gl)
    : m_limits(std::move(limits)), m_sessions(m_limits.maxSessions), m_gl(gl ? std::move(gl) : std::make_unique<GlWorker>()) {
    if (!dataDir.empty()) {
        m_persist = std::make_unique<Persistence>(dataDir, [this](const std::string& bytes, const std::string& format) {
            core::MeshLimits limits = m_limits.meshLimits;
            limits.maxFileBytes = std::max(limits.maxFileBytes, bytes.size());  // accepted once: the file limit may have changed since
            return loadUntrustedMesh(bytes, format, limits, m_limits.vdbReader);
        });
        for (auto& s : m_persist->loadSessions()) {
            m_memory.recount(*s);
            m_sessions.restore(s);
        }
        for (auto& j : m_persist->loadJobs()) m_jobs.restore(j);
        pruneJobs();
        spdlog::info("restored {} session(s) from '{}'", m_sessions.size(), dataDir);
    } else {
        m_scratch = std::filesystem::temp_directory_path() / ("volstyle-jobs-" + SessionStore::newId());
    }
}

SessionService::~SessionService() {
    // Stop the solves (a running one ends at its next iteration, queued ones before they start),
    // then free every GPU object on the GL thread while the context lives: the last short task
    // runs before the worker drains the cancelled solves, which create nothing on the way out.
    for (auto& j : m_jobs.all()) j->cancel = true;
    try {
        if (m_gl->used()) freeGpuObjects();  // nothing to free when nothing ever ran on GL
    } catch (const std::exception& e) {
        spdlog::debug("shutting down: the GPU objects were not freed on the GL thread: {}", e.what());
    }
    std::error_code ec;
    if (!m_scratch.empty()) std::filesystem::remove_all(m_scratch, ec);
}

void SessionService::freeGpuObjects() {
    m_gl->run([this](core::GpuDevice&) {
        for (auto& s : m_sessions.all()) {
            std::lock_guard lock(s->mutex);
            s->gpu.reset();
        }
        for (auto& j : m_jobs.all()) {
            std::lock_guard lock(j->mutex);
            j->preview.reset();
        }
        m_renderer.reset();
        m_stylizer.reset();
        m_translucent.reset();
        m_solveCache.reset();
    });
}

double SessionService::stylizerLookupsPerSecond() {
    std::call_once(m_stylizerSpeedOnce, [this] {
        double measured = 0;
        try {
            // Once, when the stylizer first starts on this device (not at every server start: a
            // server that never stylizes should not pay for it).
            measured = m_gl->run([this](core::GpuDevice& device) { return stylizerEngine(device).measureLookupsPerSecond(); });
        } catch (const std::exception& e) {
            spdlog::warn("the stylizer's speed could not be measured ({}); frames are estimated at {:g} lookups/s", e.what(),
                         kMinStylizerLookupsPerSecond);
        }
        m_stylizerLookupsPerSecond = std::max(measured, kMinStylizerLookupsPerSecond);
        spdlog::info("stylizer: {:.3g} lookups/s measured on this device; frame estimates use {:.3g}", measured, m_stylizerLookupsPerSecond);
    });
    return m_stylizerLookupsPerSecond;
}

double SessionService::stylizerSeconds(const core::StylizerScene& scene, const core::StylizeSettings& settings) {
    return core::Stylizer::estimatedLookups(scene, settings) / stylizerLookupsPerSecond();
}

void SessionService::saved(Session& s) {
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    if (m_persist) m_persist->saveSession(s);
    m_memory.recount(s);  // what it holds now, whatever changed
}

void SessionService::saved(const Job& j) {
    std::lock_guard lock(m_jobRecords);
    if (m_persist && !j.forgotten) m_persist->saveJob(j);
}

void SessionService::pruneJobs() {
    std::error_code ec;
    for (const auto& j : m_jobs.prune(m_limits.finishedJobsKept)) {
        {
            std::lock_guard lock(m_jobRecords);
            j->forgotten = true;
            if (m_persist) m_persist->removeJob(j->id);
            else std::filesystem::remove_all(jobFilesDir(j->id), ec);
        }
        if (auto s = m_sessions.find(j->session)) {
            std::lock_guard lock(s->mutex);
            std::erase(s->jobs, j->id);
        }
        std::shared_ptr<core::GpuVolume> preview;
        {
            std::lock_guard lock(j->mutex);
            preview = std::move(j->preview);
        }
        release(std::move(preview));
    }
}

std::shared_ptr<Session> SessionService::create(const protocol::CreateSessionRequest& request) {
    // Refuse before building the scene (a 256³ one takes seconds); add() re-checks under its lock.
    if (m_sessions.size() >= m_limits.maxSessions) throw tooManySessions(m_limits.maxSessions);
    auto s = std::make_shared<Session>();
    s->created = isoNow();
    s->scene = request.scene;
    m_memory.checkNew(size_t(request.resolution) * request.resolution * request.resolution * 9 * sizeof(float), "a new session");
    s->volume = core::makeBuiltinScene(request.builtinName(), request.resolution);  // InvalidArgument lists the scenes
    s->lighting = core::defaultLighting();
    s->versions.add(1);
    m_sessions.add(s);
    std::lock_guard lock(s->mutex);
    saved(*s);
    return s;
}

std::shared_ptr<Session> SessionService::find(const std::string& id) const {
    auto s = m_sessions.find(id);
    if (!s) throw ApiError(ErrorCode::NotFound, "no session '" + id + "'");
    return s;
}

void SessionService::remove(const std::string& id) {
    auto s = m_sessions.remove(id);
    if (!s) throw ApiError(ErrorCode::NotFound, "no session '" + id + "'");
    std::vector<std::string> jobs;
    {
        std::lock_guard lock(s->mutex);
        s->removed = true;  // from now on nothing writes it back or caches a GPU copy
        m_memory.forget(*s);
        jobs = s->jobs;
        if (m_persist) m_persist->removeSession(s->id);
    }
    s->stylizerChanged.notify_all();  // its live streams end
    bool holdsGpu = false;
    {
        std::lock_guard lock(s->mutex);
        holdsGpu = s->gpu != nullptr;
    }
    for (const auto& jid : jobs)
        if (auto j = m_jobs.find(jid)) {
            j->cancel = true;
            std::lock_guard lock(j->mutex);
            holdsGpu |= j->preview != nullptr;
        }
    if (!holdsGpu) return;  // nothing for the GL thread to free
    m_gl->run([this, s](core::GpuDevice&) {
        std::lock_guard lock(s->mutex);
        s->gpu.reset();
        dropPreviews(*s);
    });
}

core::Lighting SessionService::lighting(Session& s) const {
    std::lock_guard lock(s.mutex);
    return s.lighting;
}

core::Lighting SessionService::setLighting(Session& s, const protocol::LightingRequest& request) {
    std::lock_guard lock(s.mutex);
    s.lighting = request.resolve(s.environmentMap);
    saved(s);
    return s.lighting;
}

nlohmann::json SessionService::lightingJson(Session& s, const core::Lighting& lighting) const {
    std::lock_guard lock(s.mutex);
    return protocol::lightingToJson(lighting, s.environmentMap.get());
}

SessionView SessionService::addView(Session& s, const core::Camera& camera, std::optional<int> frame) {
    std::lock_guard lock(s.mutex);
    s.views.push_back({"v" + std::to_string(s.nextView++), camera, std::nullopt, std::nullopt, nullptr, frame});
    saved(s);
    return s.views.back();
}

SessionView SessionService::view(Session& s, const std::string& viewId) const {
    std::lock_guard lock(s.mutex);
    return findView(s, viewId);
}

void SessionService::removeView(Session& s, const std::string& viewId) {
    std::lock_guard lock(s.mutex);
    findView(s, viewId);  // 404 if absent
    std::erase_if(s.views, [&](const SessionView& v) { return v.id == viewId; });
    if (m_persist) m_persist->removeView(s.id, viewId);
    saved(s);
}

void SessionService::checkUploadSize(const std::string& bytes, const std::string& what) const {
    if (bytes.size() > m_limits.maxUploadBytes)
        throw ApiError(ErrorCode::TooLarge, what + " is " + std::to_string(bytes.size()) + " bytes; the upload limit is " +
                                                std::to_string(m_limits.maxUploadBytes) + " bytes");
}

const char* viewImageName(ViewImage kind) {
    switch (kind) {
        case ViewImage::Target: return "target";
        case ViewImage::Weights: return "weights";
        default: return "background";
    }
}

SessionView SessionService::setViewImage(Session& s, const std::string& viewId, ViewImage kind, const std::string& bytes) {
    const bool isTarget = kind == ViewImage::Target;
    const std::string what = isTarget ? "the target" : kind == ViewImage::Weights ? "the weight image" : "the background plate";
    checkUploadSize(bytes, what);
    const core::Camera camera = view(s, viewId).camera;  // 404 before any decode
    // The size is checked from the header, before any pixel is decoded, and at most
    // kConcurrentDecodes uploads decode at once: six parallel 4096² PNGs to a 64² view once took
    // 5.8 GiB to refuse.
    std::optional<DecodeSlot> slot;
    const auto checkHeader = [&](int width, int height) {
        if (width != camera.width || height != camera.height)
            throw ApiError(ErrorCode::InvalidArgument, "the image is " + std::to_string(width) + "x" + std::to_string(height) +
                                                           " but view " + viewId + " renders " + std::to_string(camera.width) +
                                                           "x" + std::to_string(camera.height));
        slot.emplace(m_decodeSlots);
    };
    core::Image image;
    try {
        const core::LoadedImage loaded = core::loadImageFromMemory(bytes.data(), bytes.size(), what, m_limits.maxImageSide, checkHeader);
        image = isTarget ? core::pictureOf(loaded) : loaded.image;  // a render EXR as a target: the picture it shows
    } catch (const Error& e) {
        throw ApiError(ErrorCode::UnsupportedMedia, e.what());  // undecodable, or over the side limit
    }
    // Weights are the target's alpha (or the weight image's first channel), a plate is radiance:
    // negative values would be solved on silently; refuse them here, where the client can fix the
    // file. (The decoder already refuses NaN and Inf.)
    const int channels = isTarget ? 4 : kind == ViewImage::Weights ? 1 : 3;
    size_t negative = 0;
    for (size_t i = 0; i < image.pixelCount(); ++i)
        for (int c = 0; c < channels; ++c) negative += image.rgba[4 * i + size_t(c)] < 0 ? 1 : 0;
    if (negative)
        throw ApiError(ErrorCode::InvalidArgument, what + " has " + std::to_string(negative) +
                                                       " negative values; colours and weights must be >= 0");
    if (kind == ViewImage::Background)  // a plate is opaque: its alpha means nothing
        for (size_t i = 0; i < image.pixelCount(); ++i) image.rgba[4 * i + 3] = 1;
    slot.reset();
    std::lock_guard lock(s.mutex);
    SessionView& v = findView(s, viewId);  // views keep their camera: the header check still holds
    const std::optional<core::Image>& held = kind == ViewImage::Target ? v.target : v.weights;
    const size_t replaced = kind == ViewImage::Background ? (v.background ? v.background->rgba.size() : 0) : (held ? held->rgba.size() : 0);
    m_memory.check(s, image.rgba.size() * sizeof(float), replaced * sizeof(float), "the " + std::string(viewImageName(kind)) + " of " + v.id);
    if (m_persist) m_persist->saveViewImage(s.id, v.id, viewImageName(kind), image);
    switch (kind) {
        case ViewImage::Target: v.target = std::move(image); break;
        case ViewImage::Weights: v.weights = std::move(image); break;
        case ViewImage::Background: v.background = std::make_shared<const core::Image>(std::move(image)); break;
    }
    saved(s);
    return v;
}

SessionView SessionService::removeViewImage(Session& s, const std::string& viewId, ViewImage kind) {
    std::lock_guard lock(s.mutex);
    SessionView& v = findView(s, viewId);
    const bool had = kind == ViewImage::Target ? v.target.has_value() : kind == ViewImage::Weights ? v.weights.has_value() : bool(v.background);
    if (!had) throw ApiError(ErrorCode::NotFound, "view " + v.id + " has no " + viewImageName(kind));
    if (m_persist) m_persist->removeViewImage(s.id, v.id, viewImageName(kind));
    if (kind == ViewImage::Target) v.target.reset();
    else if (kind == ViewImage::Weights) v.weights.reset();
    else v.background.reset();
    saved(s);
    return v;
}

void SessionService::dropPreviews(const Session& s) {
    for (const auto& jid : s.jobs) {
        auto j = m_jobs.find(jid);
        if (!j) continue;
        std::lock_guard lock(j->mutex);
        if (j->isFinished()) j->preview.reset();
    }
}

std::shared_ptr<Job> SessionService::job(const std::string& id) const {
    auto j = m_jobs.find(id);
    if (!j) throw ApiError(ErrorCode::NotFound, "no job '" + id + "'");
    return j;
}

std::shared_ptr<Job> SessionService::queueJob(Session& s) {
    checkJobQueue(s);
    pruneJobs();
    auto job = m_jobs.add(s.id);
    saved(*job);
    {
        std::lock_guard lock(s.mutex);
        s.jobs.push_back(job->id);
        saved(s);
    }
    spdlog::info("job {} queued (session {})", job->id, s.id);
    return job;
}

void SessionService::checkJobQueue(const Session& s) const {
    if (m_jobs.pending(s.id) >= m_limits.maxQueuedJobs)
        throw ApiError(ErrorCode::TooManyJobs, "session '" + s.id + "' already has " + std::to_string(m_limits.maxQueuedJobs) +
                                                   " queued jobs (the limit); wait or cancel one");
}

std::filesystem::path SessionService::jobFilesDir(const std::string& jobId) const {
    return m_persist ? m_persist->jobFilesDir(jobId) : m_scratch / jobId;
}

std::filesystem::path SessionService::jobFile(const std::string& jobId, const std::string& name) const {
    job(jobId);  // not_found for no such job
    const std::filesystem::path path = jobFilesDir(jobId) / name;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw ApiError(ErrorCode::NotFound, "job '" + jobId + "' has no file '" + name + "' (yet)");
    return path;
}

std::shared_ptr<Job> SessionService::startSolve(const std::shared_ptr<Session>& session, const core::SolveOptions& options) {
    Session& s = *session;
    checkJobQueue(s);
    {
        std::lock_guard lock(s.mutex);
        bool anyTarget = false;
        for (const auto& v : s.views) anyTarget |= v.target.has_value() && !v.frame;
        if (!anyTarget)
            throw ApiError(ErrorCode::InvalidArgument, "no view of the volume has a target (views of an animation's frames are solved by "
                                                       "POST …/animate); PUT …/views/{vid}/target first");
        // "views" names views of this session that have targets: check now, not when the job runs.
        std::vector<protocol::FieldError> problems;
        for (size_t i = 0; i < options.views.size(); ++i) {
            auto it = std::find_if(s.views.begin(), s.views.end(), [&](const SessionView& v) { return v.id == options.views[i]; });
            if (it == s.views.end()) problems.push_back({"/views/" + std::to_string(i), "no view '" + options.views[i] + "' in this session"});
            else if (!it->target) problems.push_back({"/views/" + std::to_string(i), "view '" + options.views[i] + "' has no target yet"});
            else if (it->frame)
                problems.push_back({"/views/" + std::to_string(i), "view '" + options.views[i] + "' shows frame " + std::to_string(*it->frame) +
                                                                       " of the animation: POST …/animate solves it"});
        }
        if (!problems.empty()) throw protocol::ValidationError(problems);
    }
    auto job = queueJob(s);
    m_gl->submit([this, job, session, options](core::GpuDevice& device) { runSolve(job, session, options, device); });
    return job;
}

}  // namespace volstyle::server

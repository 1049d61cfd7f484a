#include "server/service/service_context.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>

#include "core/base/errors.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"
#include "core/solve/solve_cache.h"
#include "core/stylize/stylizer.h"
#include "core/translucent/translucent_renderer.h"
#include "protocol/error_body.h"
#include "server/runtime/gl_worker.h"
#include "server/runtime/mesh_reader.h"

namespace volstyle::server {
ServiceContext::ServiceContext(ServiceLimits serviceLimits, const std::string& dataDir, std::unique_ptr<GlExecutor> executor)
    : limits(std::move(serviceLimits)), sessions(limits.maxSessions), gl(executor ? std::move(executor) : std::make_unique<GlWorker>()) {
    std::string folder = dataDir;
    if (folder.empty() && !limits.store.empty()) {  // a store needs a folder to cache it in (removed at exit, as scratch)
        scratch = std::filesystem::temp_directory_path() / ("volstyle-cache-" + SessionStore::newId());
        folder = scratch.string();
    }
    if (!folder.empty()) {
        persist = std::make_unique<Persistence>(folder, [this](const std::string& bytes, const std::string& format) {
            core::MeshLimits meshLimits = limits.meshLimits;
            meshLimits.maxFileBytes = std::max(meshLimits.maxFileBytes, bytes.size());  // accepted once: the file limit may have changed since
            return loadUntrustedMesh(bytes, format, meshLimits, limits.vdbReader);
        }, limits.store.empty() ? nullptr : openPostgresMirror(limits.store));
        for (auto& s : persist->loadSessions()) {
            memory.recount(*s);
            sessions.restore(s);
        }
        for (auto& j : persist->loadJobs()) jobs.restore(j);
        if (!limits.store.empty()) queue = openPostgresJobQueue(limits.store, limits.replica, limits.jobLease);
        pruneJobs();
        spdlog::info("restored {} session(s) from {}", sessions.size(), limits.store.empty() ? "'" + folder + "'" : persist->describe());
    } else {
        scratch = std::filesystem::temp_directory_path() / ("volstyle-jobs-" + SessionStore::newId());
    }
}

void ServiceContext::shutdown() {
    if (!gl) return;
    // Stop the solves (a running one ends at its next iteration, queued ones before they start),
    // then free every GPU object on the GL thread while the context lives. The freeing waits for
    // the running job to end: as a short task between a cancelled solve's iterations, it freed
    // the solve cache that the solve still wrote its last state to (a heap corruption). Queued
    // jobs then end at once, cancelled, without touching the GPU.
    workAheadStopped = true;  // no idle task makes GPU objects after freeGpuObjects() below
    std::vector<std::shared_ptr<Job>> local;  // those this replica runs (not copies of other replicas')
    for (auto& j : jobs.all()) {
        std::lock_guard lock(j->mutex);
        if (!j->remote) local.push_back(j);
    }
    handBackJobs();
    for (auto& j : jobs.all()) j->cancel = true;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    bool stopped = true;
    for (auto& j : local) {
        std::unique_lock lock(j->mutex);
        stopped &= j->changed.wait_until(lock, deadline, [&] { return j->state != JobState::Running; });
    }
    if (!stopped) spdlog::warn("shutting down: a job still runs after 60 s; its GPU objects are left to the process's end");
    try {
        if (stopped && gl->used()) freeGpuObjects();  // nothing to free when nothing ever ran on GL
    } catch (const std::exception& e) {
        spdlog::debug("shutting down: the GPU objects were not freed on the GL thread: {}", e.what());
    }
    gl.reset();  // drains the queued work (it calls into the services: they must still live)
}

void ServiceContext::handBackJobs() {
    if (!queue) return;
    // A replica that stops hands its unfinished jobs back rather than ending them cancelled:
    // their copies here become remote (they write nothing more) and their leases lapse now, so
    // another replica runs them again at once.
    std::vector<std::string> ids;
    for (auto& j : jobs.all()) {
        std::lock_guard lock(j->mutex);
        if (j->remote || j->isFinished()) continue;
        j->remote = true;
        j->relay = nullptr;
        ids.push_back(j->id);
    }
    try {
        queue->release(ids);
        if (!ids.empty()) spdlog::info("shutting down: {} unfinished job(s) handed back to the queue", ids.size());
    } catch (const std::exception& e) {
        spdlog::warn("shutting down: the job leases were not handed back ({}); they lapse in {} ms", e.what(), queue->lease().count());
    }
}

ServiceContext::~ServiceContext() {
    shutdown();
    std::error_code ec;
    if (!scratch.empty()) std::filesystem::remove_all(scratch, ec);
}

void ServiceContext::freeGpuObjects() {
    gl->run([this](core::GpuDevice&) {
        for (auto& s : sessions.all()) {
            std::lock_guard lock(s->mutex);
            s->volume.gpu.reset();
        }
        for (auto& j : jobs.all()) {
            std::lock_guard lock(j->mutex);
            j->preview.reset();
        }
        rendererEngine.reset();
        stylizer.reset();
        translucent.reset();
        solveCache.reset();
        prefetched.clear();  // it named what the cache held
    });
}

void ServiceContext::saved(Session& s) {
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    if (persist) persist->saveSession(s);
    memory.recount(s);  // what it holds now, whatever changed
    prefetchSolve(s);
}

std::shared_ptr<Session> ServiceContext::find(const std::string& id) {
    auto s = sessions.find(id);
    if (persist && persist->hasMirror()) s = freshFromStore(id, std::move(s));
    if (!s) throw ApiError(ErrorCode::NotFound, "no session '" + id + "'");
    return s;
}

std::shared_ptr<Session> ServiceContext::freshFromStore(const std::string& id, std::shared_ptr<Session> held) {
    // Replicas share the store (issue #41): a session another replica made or changed is read
    // from it here, one query per request when nothing changed.
    if (!SessionStore::isStoreId(id)) return held;
    std::optional<uint64_t> stamp;
    if (held) {
        // Read with the session's lock held: a save here commits and takes its new stamp under
        // it, so the two are compared at one moment (else a save between them looks like
        // another replica's, and requests in flight on this copy would be cut off).
        std::lock_guard lock(held->mutex);
        stamp = persist->storedStamp(id);
        if (stamp ? *stamp == held->storeStamp : held->storeStamp == 0) return held;  // the newest (or being created here)
    } else {
        stamp = persist->storedStamp(id);
    }
    if (!stamp) {  // stored once, gone now: another replica deleted it
        if (held && sessions.remove(id) == held) retire(*held);
        return nullptr;
    }
    std::lock_guard lock(storeLoads);  // one load at a time: two requests for a stale session load it once
    if (auto again = sessions.find(id); again && again != held) return again;  // loaded meanwhile
    std::shared_ptr<Session> fresh = persist->loadFromStore(id);
    if (!fresh) return held;
    if (held) retire(*held);
    {
        std::lock_guard freshLock(fresh->mutex);
        memory.recount(*fresh);
    }
    sessions.restore(fresh);
    spdlog::info("session {}: read from the store ({})", id, held ? "another replica changed it" : "made elsewhere");
    return fresh;
}

core::Lighting ServiceContext::lighting(Session& s) const {
    std::lock_guard lock(s.mutex);
    return s.light.lighting;
}

SessionView ServiceContext::view(Session& s, const std::string& viewId) const {
    std::lock_guard lock(s.mutex);
    return findView(s, viewId);
}

void ServiceContext::checkUploadSize(const std::string& bytes, const std::string& what) const {
    if (bytes.size() > limits.maxUploadBytes)
        throw ApiError(ErrorCode::TooLarge, what + " is " + std::to_string(bytes.size()) + " bytes; the upload limit is " +
                                                std::to_string(limits.maxUploadBytes) + " bytes");
}

void ServiceContext::dropPreviews(const Session& s) {
    for (const auto& jid : s.jobs) {
        auto j = jobs.find(jid);
        if (!j) continue;
        std::lock_guard lock(j->mutex);
        if (j->isFinished()) j->preview.reset();
    }
}

std::filesystem::path ServiceContext::jobFilesDir(const std::string& jobId) const {
    return persist ? persist->jobFilesDir(jobId) : scratch / jobId;
}

std::shared_ptr<core::GpuVolume> ServiceContext::commitVersion(Session& s, core::Volume volume, int shows) {
    // An edit: what was shown can be brought back by an undo; what was undone cannot be redone.
    s.volume.undo.push_back(s.volume.shows);
    if (s.volume.undo.size() > kMaxUndoSteps) s.volume.undo.erase(s.volume.undo.begin());
    s.volume.redo.clear();
    return commitStep(s, std::move(volume), shows);
}

std::shared_ptr<core::GpuVolume> ServiceContext::commitStep(Session& s, core::Volume volume, int shows) {
    const int n = s.volume.versions.newest() + 1;  // after damaged ones too: numbers are never reused
    s.volume.versions.retire(s.volume.version, std::move(s.volume.current));
    s.volume.current = std::move(volume);
    s.volume.version = n;
    s.volume.shows = shows > 0 ? shows : n;
    s.volume.versions.add(n);
    saved(s);
    shownChanged(s);
    if (s.stylizer.scene.volume) stylizerChanged(s);  // its medium is the session's volume: live frames follow
    return std::move(s.volume.gpu);
}

void ServiceContext::retire(Session& s) {
    std::shared_ptr<core::GpuVolume> gpu;
    {
        std::lock_guard lock(s.mutex);
        s.removed = true;  // its streams end; work queued on it answers not_found
        s.changed.notify_all();
        memory.forget(s);
        gpu = std::move(s.volume.gpu);  // freed on the GL thread, never by an HTTP thread's last reference
        for (const std::string& j : s.jobs)
            if (auto job = jobs.find(j)) job->cancel = true;
    }
    release(std::move(gpu));
}

void ServiceContext::release(std::shared_ptr<core::GpuVolume> gpu) {
    if (gpu) gl->run([gpu = std::move(gpu)](core::GpuDevice&) mutable { gpu.reset(); });
}

core::Renderer& ServiceContext::renderer(core::GpuDevice& device) {
    if (!rendererEngine) rendererEngine = std::make_unique<core::Renderer>(device);
    return *rendererEngine;
}

std::shared_ptr<core::GpuVolume> ServiceContext::sessionGpu(Session& s) {
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    if (!s.volume.gpu) s.volume.gpu = std::make_shared<core::GpuVolume>(s.volume.current);
    return s.volume.gpu;
}

std::shared_ptr<core::GpuVolume> ServiceContext::lockedSessionGpu(Session& s) {
    // The lock covers only finding (or uploading) the GPU copy, not the render: reads of the
    // session (a VDB download, its JSON) never wait for GL work. Locking on the GL thread is safe
    // even between a solve's iterations: the solve holds no session lock then.
    std::lock_guard lock(s.mutex);
    return sessionGpu(s);
}

void ServiceContext::shownChanged(Session& s) {
    ++s.shownRevision;
    s.changed.notify_all();
}

void ServiceContext::stylizerChanged(Session& s, bool history) {
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    if (persist) persist->commitStylizer(s, history, s.stylizer.revision + 1);
    ++s.stylizer.revision;
    s.changed.notify_all();
}

core::Stylizer& ServiceContext::stylizerEngine(core::GpuDevice& device) {
    if (!stylizer) stylizer = std::make_unique<core::Stylizer>(device);
    return *stylizer;
}

}  // namespace volstyle::server

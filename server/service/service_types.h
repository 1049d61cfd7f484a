#pragma once
/// \file service_types.h
/// The values the session services take and return (issue #36: core and protocol values, no
/// JSON): their limits, and what stylizer calls answer.

#include <chrono>
#include <mutex>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <semaphore>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/render/renderer.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_options.h"
#include "core/volume/volume.h"
#include "protocol/render_json.h"
#include "protocol/requests.h"
#include "protocol/response_values.h"
#include "server/runtime/gl_executor.h"
#include "server/store/job_queue.h"
#include "server/state/job_store.h"
#include "server/service/memory_budget.h"
#include "server/store/persistence.h"
#include "server/state/session_store.h"
#include "server/runtime/vdb_reader.h"
#include "server/state/stylizer_state.h"

namespace volstyle::core {
class Stylizer;
class SolveCache;
class TranslucentRenderer;
struct TranslucentSettings;
struct StylizedFrame;
}  // namespace volstyle::core

namespace volstyle::server {

// What stylizer calls answer (protocol/response_values.h).
using protocol::AddedTfConstraint;
using protocol::OccluderMeshInfo;
using protocol::StylizerPick;
using protocol::TransferImageInfo;

// The API's error and job vocabulary, as every service names it.
using protocol::ApiError;
using protocol::ErrorCode;
using protocol::JobEvent;
using protocol::JobState;

struct ServiceLimits {
    size_t maxSessions = 64;
    size_t maxQueuedJobs = 4;  ///< per session
    size_t maxUploadBytes = size_t(512) << 20;
    int maxImageSide = 4096;
    core::VolumeLimits volumeLimits;
    /// Occluder meshes: each file (also within maxUploadBytes) and its vertices and triangles;
    /// maxVertices also bounds the vertices of all a session's uploads together.
    core::MeshLimits meshLimits;
    size_t maxMeshesPerSession = 16;
    /// Seconds a render or preview may hold the GL thread (over: 422 over_budget); <= 0: unbounded.
    double renderBudgetSeconds = 60;
    VdbReaderOptions vdbReader;  ///< uploads are read in a child process first (vdb_reader.h)
    /// Finished jobs kept (memory and disk; GET /jobs/{id} of an older one: 404). Unfinished
    /// jobs are always kept.
    size_t finishedJobsKept = 256;
    /// GPU memory for the parts one solve leaves for the next (core/solve/solve_cache.h), shared by
    /// every session: the keys name content, not sessions. 0: every solve starts cold.
    size_t solveCacheBytes = size_t(1) << 30;
    /// Render what a session's next solve needs while the GL thread is idle (solve_prefetch.cpp).
    bool prefetchSolves = true;
    /// Decoded bytes a session, and all sessions, may hold (memory_budget.h; over: 507).
    MemoryLimits memory;
    /// Where sessions and jobs are kept beside the data folder (issue #41): "" (the folder alone)
    /// or a PostgreSQL connection string (postgresql://…), the folder then a cache of it.
    std::string store;
    /// With a store: this replica's name (logs, the job queue's owner tokens) and how long a job's
    /// lease lasts unrenewed (another replica runs a job again that long after its replica died).
    std::string replica = "volstyle";
    std::chrono::milliseconds jobLease{10000};
};

/// Where a job comes from (issue #41): a request — its kind and its body as sent, kept in the job
/// queue's row so that another replica can run it again if this one dies — or, `adopted`, a job
/// claimed from the queue and run again here from that request.
struct JobOrigin {
    std::string kind;     ///< "solve", "animate", "frames-render", "sequence"
    std::string request;  ///< the body as sent (JSON text); empty: the job cannot run again
    std::shared_ptr<Job> adopted;
};

enum class ViewImage { Target, Weights, Background };
/// "target", "weights", "background": its name in routes, files and "has_…" fields.
const char* viewImageName(ViewImage kind);

/// What a session's stylizer renders (a copy: the meshes are shared, not copied).
struct StylizerSnapshot {
    core::StylizerScene scene;
    std::vector<std::string> meshRefs;
    uint64_t revision = 0;
};

/// A VDB to download, with a tag naming its content (an ETag's value): equal tags, equal volumes.
struct VdbDownload {
    std::string bytes;
    std::string tag;
};

}  // namespace volstyle::server

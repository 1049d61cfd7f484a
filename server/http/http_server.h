#pragma once
/// \file http_server.h
/// `volstyle serve`: the HTTP/JSON API of SPEC §3 over cpp-httplib. This file is the shell —
/// options, request ids, the bearer token, the error body for every failure, static files — and
/// the routes live by resource under server/http/routes/, calling the session services (server/service/services.h).

#include <memory>
#include <string>
#include <vector>

#include "core/volume/volume.h"
#include "server/http/guarded_http_server.h"
#include "server/http/route_table.h"
#include "server/service/memory_budget.h"

namespace volstyle::server {

struct ServerOptions {
    std::string host = "127.0.0.1";
    int port = 8080;                 ///< 0: any free port (tests)
    std::string token;               ///< required when host is not loopback
    std::string webDir = "web";
    std::string dataDir = "volstyle-data";  ///< empty: keep everything in memory (tests)
    /// "" (the data folder alone) or postgresql://… (committed there; the folder is its cache).
    std::string store;
    std::string replica = "volstyle";  ///< with a store: this replica's name in logs and job leases
    double jobLeaseSeconds = 10;      ///< with a store: a job's lease (another replica runs it again once lapsed)
    size_t maxSessions = 64;
    size_t maxJsonBytes = 1 << 20;   ///< 1 MiB
    size_t maxUploadBytes = size_t(512) << 20;  ///< images and VDBs: 512 MiB
    int maxImageSide = 4096;
    core::VolumeLimits volumeLimits;
    MemoryLimits memory;             ///< decoded bytes per session and in all (memory_budget.h)
    /// Vertices of one occluder mesh, and of all a session's meshes together (triangles: twice).
    size_t maxMeshVertices = 4'000'000;
    int httpThreads = 48;            ///< HTTP worker threads (an open event stream holds one)
    int maxEventStreams = 16;        ///< open event streams in all (below httpThreads)
    int maxEventStreamsPerClient = 8;
    double eventKeepAliveSeconds = 15;  ///< a job's quiet event stream sends a comment this often
    ConnectionLimits connections;    ///< read deadlines and connections per client (guarded_http_server.h)
    double renderBudgetSeconds = 60;  ///< a render's limit on the GL thread (422 over_budget); <= 0: none
    bool prefetchSolves = true;       ///< render a session's next solve's views while the GL thread is idle
    /// The volstyle binary that reads uploaded VDBs in a child process (`serve` sets itself);
    /// empty: read them in this process (a crash inside OpenVDB then ends the server).
    std::string vdbReader;
    size_t finishedJobsKept = 256;  ///< older finished jobs are forgotten (GET /jobs/{id}: 404)
};

class HttpServer {
public:
    /// Checks the options (a non-loopback host needs a token: InvalidArgument otherwise) and
    /// starts the GL thread (GpuError if no context).
    explicit HttpServer(ServerOptions options);
    ~HttpServer();

    int bind();     ///< binds host:port (port 0: any free one) and returns the port
    void listen();  ///< serves until stop(); call after bind()
    void stop();

    /// Every API route, by method and path pattern (the OpenAPI test compares the document with it).
    std::vector<RouteEntry> routes() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace volstyle::server

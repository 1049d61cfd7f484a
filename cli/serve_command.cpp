// `volstyle serve`: the HTTP/JSON server (SPEC §3–4). SIGINT/SIGTERM stop it cleanly: a thread
// waits for the signals (blocked everywhere else) and stops the listener.

#include <malloc.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>
#include <spdlog/spdlog.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <thread>

#include "core/base/errors.h"
#include "cli/cli.h"
#include "protocol/build_version.h"
#include "server/http/http_server.h"
#include "server/store/file_mirror.h"

namespace volstyle::cli {

namespace {

const CommandSpec kServe{
    "serve",
    "the HTTP/JSON server and the painting page",
    "[options]",
    "Runs the HTTP/JSON server (docs/API.md) and serves the painting page at its root. Every change\n"
    "is written to --data-dir before it is answered; a restart restores every session.",
    {
        {"host", "ADDR", "address to listen on; default 127.0.0.1 (any other needs --token)"},
        {"port", "N", "port; default 8080 (0: any free port, printed at start)"},
        {"token", "T", "require 'Authorization: Bearer T' on /api (also $VOLSTYLE_TOKEN); default none"},
        {"data-dir", "DIR", "where sessions are kept; default ./volstyle-data"},
        {"store", "URL", "also keep them in PostgreSQL (postgresql://user@host:port/db): committed there before each answer, the data folder its cache (docs/DEPLOY.md); default none"},
        {"replica", "NAME", "with --store: this replica's name in logs and job leases; default HOST:PID"},
        {"job-lease", "SECONDS", "with --store: a running job's lease; another replica runs it again once it lapses unrenewed; default 10"},
        {"web-dir", "DIR", "the page's folder; default the installed share/volstyle/web, else the source tree's web/"},
        {"render-budget", "S", "seconds one render may hold the GL thread (422 over_budget past it; 0: no limit); default 60"},
        {"prefetch", "on|off", "make what a session's next solve needs first (each view's render and, on a CPU rasterizer, rows of W) while the GL thread is idle, so a solve after painting starts from it; default on"},
        {"max-sessions", "N", "sessions at once; default 64"},
        {"max-upload-mib", "N", "largest VDB or image upload, MiB; default 512"},
        {"max-image-side", "N", "largest target or render side, pixels; default 4096"},
        {"max-mesh-vertices", "N", "vertices of an occluder mesh, and of a session's meshes together; default 4000000"},
        {"max-voxels", "N", "largest volume stored dense (its box), voxels; a larger box is stored sparse; default 16777216 (256^3)"},
        {"max-active-voxels", "N", "largest sparse volume: voxels of its active 8^3 bricks; default 67108864 (64 M)"},
        {"storage", "MODE", "how uploaded volumes are stored: auto (dense while the box fits --max-voxels), dense or sparse; default auto"},
        {"max-json-kib", "N", "largest JSON body, KiB; default 1024"},
        {"session-memory-mib", "N", "decoded frames, versions, meshes and images one session may hold, MiB (507 past it); default 2048"},
        {"memory-mib", "N", "the same for all sessions together, MiB; default 8192"},
    },
    "  volstyle serve --port 8080\n"};

/// A whole number in [lo, hi] for `--flag`, or InvalidArgument naming the range.
double wholeNumber(const Arguments& args, const std::string& flag, double fallback, double lo, double hi) {
    const double v = args.number(flag, fallback);
    if (v < lo || v > hi || v != std::floor(v))
        throw InvalidArgument("--" + flag + " must be a whole number in [" + fmt::format("{:g}", lo) + ", " + fmt::format("{:g}", hi) + "]");
    return v;
}

/// `--flag on|off`, or InvalidArgument.
bool onOrOff(const Arguments& args, const std::string& flag, bool fallback) {
    const std::string v = args.get(flag, fallback ? "on" : "off");
    if (v != "on" && v != "off") throw InvalidArgument("--" + flag + " must be on or off");
    return v == "on";
}

}  // namespace

const CommandSpec& serveCommand() { return kServe; }

namespace {

/// A replica's name by default: the machine's, and the process's id.
std::string defaultReplicaName() {
    char host[256] = {};
    if (gethostname(host, sizeof host - 1) != 0) std::snprintf(host, sizeof host, "volstyle");
    return std::string(host) + ":" + std::to_string(getpid());
}

/// --store: empty (the data folder alone) or a PostgreSQL URL.
std::string storeUrl(const Arguments& args) {
    const std::string url = args.get("store", "");
    if (!url.empty() && url.rfind("postgresql://", 0) != 0 && url.rfind("postgres://", 0) != 0)
        throw InvalidArgument("serve: --store takes a postgresql:// URL (the data folder is the default store)");
    return url;
}

/// --store, --replica, --job-lease; with a store, log lines name the replica (replicas' logs merge).
void storeOptions(const Arguments& args, server::ServerOptions& opt) {
    opt.store = storeUrl(args);
    opt.replica = args.get("replica", defaultReplicaName());
    opt.jobLeaseSeconds = args.number("job-lease", opt.jobLeaseSeconds);
    if (!(opt.jobLeaseSeconds >= 0.3 && opt.jobLeaseSeconds <= 3600))
        throw InvalidArgument("--job-lease must be a number of seconds from 0.3 to 3600");
    if (!opt.store.empty()) spdlog::set_pattern("[%Y-%m-%d %H:%M:%S.%e] [" + opt.replica + "] [%l] %v");
}

}  // namespace

int runServe(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, kServe);
    if (printHelpIfAsked(args, kServe)) return 0;
    server::ServerOptions opt;
    opt.host = args.get("host", opt.host);
    opt.port = int(wholeNumber(args, "port", opt.port, 0, 65535));
    const char* envToken = std::getenv("VOLSTYLE_TOKEN");
    opt.token = args.get("token", envToken ? envToken : "");
    opt.webDir = args.has("web-dir") ? args.get("web-dir") : defaultWebDir();
    opt.dataDir = args.get("data-dir", opt.dataDir);
    storeOptions(args, opt);
    opt.maxSessions = size_t(wholeNumber(args, "max-sessions", double(opt.maxSessions), 1, 1e6));
    opt.maxUploadBytes = size_t(wholeNumber(args, "max-upload-mib", double(opt.maxUploadBytes >> 20), 1, 1 << 20)) << 20;
    opt.maxImageSide = int(wholeNumber(args, "max-image-side", opt.maxImageSide, 16, 65536));
    opt.maxMeshVertices = size_t(wholeNumber(args, "max-mesh-vertices", double(opt.maxMeshVertices), 3, 1e8));
    opt.volumeLimits.maxVoxels = int64_t(wholeNumber(args, "max-voxels", double(opt.volumeLimits.maxVoxels), 1, 1e10));
    opt.volumeLimits.maxActiveVoxels = int64_t(wholeNumber(args, "max-active-voxels", double(int64_t(64) << 20), 512, 1e11));
    opt.volumeLimits.storage = core::volumeStorageNamed(args.get("storage", "auto"));
    opt.maxJsonBytes = size_t(wholeNumber(args, "max-json-kib", double(opt.maxJsonBytes >> 10), 1, 1 << 20)) << 10;
    opt.memory.perSession = size_t(wholeNumber(args, "session-memory-mib", double(opt.memory.perSession >> 20), 1, 1 << 24)) << 20;
    opt.memory.total = size_t(wholeNumber(args, "memory-mib", double(opt.memory.total >> 20), 1, 1 << 24)) << 20;
    // This process's own image, even if the file on disk is replaced while it runs (a rebuild or
    // an upgrade: the soak saw uploads fail while the binary was relinked). posix_spawn execs in
    // the child, whose /proc/self/exe is still this binary.
    opt.vdbReader = "/proc/self/exe";
    opt.renderBudgetSeconds = args.number("render-budget", opt.renderBudgetSeconds);
    opt.prefetchSolves = onOrOff(args, "prefetch", true);
    if (!(opt.renderBudgetSeconds >= 0) || !std::isfinite(opt.renderBudgetSeconds))
        throw InvalidArgument("--render-budget must be a number of seconds >= 0 (0: no limit)");

    // Block the stop signals before any thread starts, so only the waiter below receives them.
    sigset_t stopSignals;
    sigemptyset(&stopSignals);
    sigaddset(&stopSignals, SIGINT);
    sigaddset(&stopSignals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);

    // Volumes and images above 256 KiB are mapped and unmapped on their own, not carved out of
    // (and kept in) the malloc arenas: glibc's threshold otherwise rises to the largest block
    // freed, and a long-running server holds on to every size it has seen.
    ::mallopt(M_MMAP_THRESHOLD, 256 * 1024);
    spdlog::set_level(std::getenv("VOLSTYLE_LOG_LEVEL") ? spdlog::get_level() : spdlog::level::info);
    server::HttpServer server(opt);
    const int bound = server.bind();
    std::thread waiter([&] {
        int sig = 0;
        sigwait(&stopSignals, &sig);
        spdlog::info("signal {}: stopping", sig);
        server.stop();
    });
    std::cout << "volstyle: serving http://" << opt.host << ":" << bound << "/ (volstyle " << protocol::versionString() << ", page from "
              << (opt.webDir.empty() ? std::string("nowhere: no web folder found; pass --web-dir") : opt.webDir) << ", data in "
              << (opt.dataDir.empty() ? std::string("memory") : opt.dataDir)
              << (opt.store.empty() ? "" : ", kept in " + server::withoutPassword(opt.store)) << ")" << std::endl;
    server.listen();
    // listen() also returns if the listener fails; wake the waiter in that case.
    pthread_kill(waiter.native_handle(), SIGTERM);
    waiter.join();
    return 0;
}

}  // namespace volstyle::cli

// `volstyle serve`: the HTTP/JSON server (SPEC §3–4). SIGINT/SIGTERM stop it cleanly: a thread
// waits for the signals (blocked everywhere else) and stops the listener.

#include <malloc.h>
#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <thread>

#include "core/base/errors.h"
#include "server/cli.h"
#include "server/http_server.h"

namespace volstyle::server {

int runServe(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, {"host", "port", "token", "web-dir", "data-dir", "render-budget"}, {"help"});
    if (args.has("help")) {
        std::cout << "usage: volstyle serve [--host 127.0.0.1] [--port 8080] [--data-dir volstyle-data] [--token T]\n"
                     "                      [--web-dir web] [--render-budget 60]\n"
                     "  --render-budget S  seconds one render may hold the GL thread (422 over_budget past it; 0: no limit)\n";
        return 0;
    }
    ServerOptions opt;
    opt.host = args.get("host", opt.host);
    const double port = args.number("port", opt.port);
    if (port < 0 || port > 65535 || port != std::floor(port)) throw InvalidArgument("--port must be in [0, 65535]");
    opt.port = int(port);
    const char* envToken = std::getenv("VOLSTYLE_TOKEN");
    opt.token = args.get("token", envToken ? envToken : "");
    opt.webDir = args.get("web-dir", opt.webDir);
    opt.dataDir = args.get("data-dir", opt.dataDir);
    // This process's own image, even if the file on disk is replaced while it runs (a rebuild or
    // an upgrade: the soak saw uploads fail while the binary was relinked). posix_spawn execs in
    // the child, whose /proc/self/exe is still this binary.
    opt.vdbReader = "/proc/self/exe";
    opt.renderBudgetSeconds = args.number("render-budget", opt.renderBudgetSeconds);
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
    HttpServer server(opt);
    const int bound = server.bind();
    std::thread waiter([&] {
        int sig = 0;
        sigwait(&stopSignals, &sig);
        spdlog::info("signal {}: stopping", sig);
        server.stop();
    });
    std::cout << "volstyle: serving http://" << opt.host << ":" << bound << "/" << std::endl;
    server.listen();
    // listen() also returns if the listener fails; wake the waiter in that case.
    pthread_kill(waiter.native_handle(), SIGTERM);
    waiter.join();
    return 0;
}

}  // namespace volstyle::server

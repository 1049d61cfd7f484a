#include "server/vdb_reader.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>

#include "core/base/errors.h"
#include "core/volume/vdb_io.h"
#include "server/cli.h"

extern char** environ;

namespace volstyle::server {
namespace {

enum ReaderStatus { kLoads = 0, kOverLimits = 3, kInvalid = 4, kUnreadable = 5 };

/// Runs `argv` with stderr captured; returns the wait status (SIGKILLs the child past `seconds`).
int runChild(const std::vector<std::string>& argv, double seconds, std::string& errors, bool& timedOut) {
    int pipeFds[2];
    if (::pipe2(pipeFds, O_CLOEXEC) != 0) throw IoError("cannot start the VDB reader: pipe failed");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipeFds[1], STDERR_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_t pid = -1;
    const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipeFds[1]);
    if (rc != 0) {
        ::close(pipeFds[0]);
        throw IoError(std::string("cannot start the VDB reader '") + argv[0] + "': " + std::strerror(rc));
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    timedOut = false;
    char buf[4096];
    for (;;) {
        const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
        if (left <= 0) {
            timedOut = true;
            ::kill(pid, SIGKILL);
            break;
        }
        pollfd p{pipeFds[0], POLLIN, 0};
        if (::poll(&p, 1, int(std::min(left * 1000, 1000.0)) + 1) < 0 && errno != EINTR) break;
        if (!(p.revents & (POLLIN | POLLHUP))) continue;
        const ssize_t n = ::read(pipeFds[0], buf, sizeof buf);
        if (n <= 0) break;  // the child closed stderr: it is exiting
        if (errors.size() < 16384) errors.append(buf, size_t(n));
    }
    ::close(pipeFds[0]);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
}

std::string trimmed(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    return s;
}

}  // namespace

namespace {

/// Reads `path` in the child first (with --frames: as an animation); throws what it refused.
void checkInChild(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader, bool frames) {
    if (!reader.executable.empty()) {
        std::string errors;
        bool timedOut = false;
        std::vector<std::string> argv{reader.executable, "read-vdb", path, "--max-voxels", std::to_string(limits.maxVoxels),
                                      "--max-memory-mib", std::to_string(reader.maxAddressSpaceMiB)};
        if (frames) argv.push_back("--frames");
        const int status = runChild(argv, reader.seconds, errors, timedOut);
        const std::string why = trimmed(errors);
        if (timedOut)
            throw InvalidArgument("reading " + path + " took over " + fmt::format("{:g}", reader.seconds) +
                                  " s; the file is damaged or too complex");
        if (WIFSIGNALED(status))
            throw IoError("reading " + path + " crashed the VDB reader (signal " + std::to_string(WTERMSIG(status)) +
                          ", inside OpenVDB): the file is damaged or malicious");
        const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        if (code == kOverLimits) throw LimitExceeded(why);
        if (code == kInvalid) throw InvalidArgument(why);
        if (code == kUnreadable) throw IoError(why.empty() ? "the VDB reader failed on " + path : why);
        if (code != kLoads) {
            // Any other status is an abnormal end (a sanitizer build reports OpenVDB's own memory
            // errors and exits 66, for one): a crash of the reader, without its stderr in the answer.
            throw IoError("reading " + path + " crashed the VDB reader (exit status " + std::to_string(code) +
                          ", inside OpenVDB): the file is damaged or malicious");
        }
    }
}

}  // namespace

core::Volume loadUntrustedVdb(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader) {
    checkInChild(path, limits, reader, false);
    return core::loadVdb(path, limits);  // the reader succeeded on these bytes: so does this
}

std::map<int, core::Volume> loadUntrustedVdbFrames(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader) {
    checkInChild(path, limits, reader, true);
    return core::loadVdbFrames(path, limits);
}

int runReadVdb(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, {"max-voxels", "max-memory-mib"}, {"frames"});
    if (args.positional.size() != 1) throw InvalidArgument("usage: volstyle read-vdb FILE --max-voxels N [--max-memory-mib M]");
    core::VolumeLimits limits;
    limits.maxVoxels = int64_t(args.number("max-voxels", double(limits.maxVoxels)));
    const double mib = args.number("max-memory-mib", 4096);
    const rlim_t bytes = rlim_t(mib) << 20;
    const rlimit cap{bytes, bytes};
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
    ::setrlimit(RLIMIT_AS, &cap);  // a request for terabytes fails here, not on the machine
#else
    (void)cap;  // ASan and TSan reserve terabytes of shadow address space: no limit in those builds
#endif
    try {
        if (args.has("frames")) {
            if (core::loadVdbFrames(args.positional[0], limits).empty())
                throw InvalidArgument("the file holds no grids stamped with a frame (density.12, vel_12, or a 'frame' metadata entry)");
        } else {
            core::loadVdb(args.positional[0], limits);
        }
        return kLoads;
    } catch (const LimitExceeded& e) {
        std::cerr << e.what() << "\n";
        return kOverLimits;
    } catch (const InvalidArgument& e) {
        std::cerr << e.what() << "\n";
        return kInvalid;
    } catch (const std::bad_alloc&) {
        std::cerr << "reading " << args.positional[0] << " needs over " << mib << " MiB; the file is damaged or too large\n";
        return kInvalid;
    } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
        return kUnreadable;
    }
}

}  // namespace volstyle::server

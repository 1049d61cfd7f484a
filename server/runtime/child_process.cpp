#include "server/runtime/child_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <iostream>

#include "core/base/errors.h"

extern char** environ;

namespace volstyle::server {

ChildOutcome runChild(const std::vector<std::string>& argv, double seconds) {
    ChildOutcome out;
    int pipeFds[2];
    if (::pipe2(pipeFds, O_CLOEXEC) != 0) throw IoError("cannot start the reader process: pipe failed");
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
        throw IoError(std::string("cannot start the reader process '") + argv[0] + "': " + std::strerror(rc));
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    char buf[4096];
    for (;;) {
        const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
        if (left <= 0) {
            out.timedOut = true;
            ::kill(pid, SIGKILL);
            break;
        }
        pollfd p{pipeFds[0], POLLIN, 0};
        if (::poll(&p, 1, int(std::min(left * 1000, 1000.0)) + 1) < 0 && errno != EINTR) break;
        if (!(p.revents & (POLLIN | POLLHUP))) continue;
        const ssize_t n = ::read(pipeFds[0], buf, sizeof buf);
        if (n <= 0) break;  // the child closed stderr: it is exiting
        if (out.errors.size() < 16384) out.errors.append(buf, size_t(n));
    }
    ::close(pipeFds[0]);
    while (::waitpid(pid, &out.waitStatus, 0) < 0 && errno == EINTR) {
    }
    while (!out.errors.empty() && (out.errors.back() == '\n' || out.errors.back() == ' ')) out.errors.pop_back();
    return out;
}

void throwChildFailure(const ChildOutcome& o, const std::string& what, const std::string& reader, const std::string& library,
                       double seconds) {
    if (o.timedOut)
        throw InvalidArgument("reading " + what + " took over " + fmt::format("{:g}", seconds) + " s; the file is damaged or too complex");
    if (WIFSIGNALED(o.waitStatus))
        throw IoError("reading " + what + " crashed the " + reader + " reader (signal " + std::to_string(WTERMSIG(o.waitStatus)) +
                      ", inside " + library + "): the file is damaged or malicious");
    const int code = WIFEXITED(o.waitStatus) ? WEXITSTATUS(o.waitStatus) : -1;
    if (code == kChildLoads) return;
    if (code == kChildOverLimits) throw LimitExceeded(o.errors);
    if (code == kChildInvalid) throw InvalidArgument(o.errors);
    if (code == kChildUnreadable) throw IoError(o.errors.empty() ? "the " + reader + " reader failed on " + what : o.errors);
    // Any other status is an abnormal end (a sanitizer build reports a library's own memory
    // errors and exits 66, for one): a crash of the reader, without its stderr in the answer.
    throw IoError("reading " + what + " crashed the " + reader + " reader (exit status " + std::to_string(code) + ", inside " +
                  library + "): the file is damaged or malicious");
}

void limitChildMemory(double mib) {
    const rlim_t bytes = rlim_t(mib) << 20;
    const rlimit cap{bytes, bytes};
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
    ::setrlimit(RLIMIT_AS, &cap);  // a request for terabytes fails here, not on the machine
#else
    (void)cap;
#endif
}

int childExitStatus(const std::function<void()>& read, const std::string& what, double mib) {
    try {
        read();
        return kChildLoads;
    } catch (const LimitExceeded& e) {
        std::cerr << e.what() << "\n";
        return kChildOverLimits;
    } catch (const InvalidArgument& e) {
        std::cerr << e.what() << "\n";
        return kChildInvalid;
    } catch (const std::bad_alloc&) {
        std::cerr << "reading " << what << " needs over " << mib << " MiB; the file is damaged or too large\n";
        return kChildInvalid;
    } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
        return kChildUnreadable;
    }
}

}  // namespace volstyle::server

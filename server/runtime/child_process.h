#pragma once
/// \file child_process.h
/// Untrusted files are parsed in a child process (`volstyle read-vdb`, `volstyle read-mesh`):
/// a parser that crashes, overflows its stack, asks for terabytes or loops ends the child, not the
/// server. The child's exit status says what it found (ChildStatus); anything else is a crash.

#include <functional>
#include <string>
#include <vector>

namespace volstyle::server {

/// What a reader child exits with.
enum ChildStatus { kChildLoads = 0, kChildOverLimits = 3, kChildInvalid = 4, kChildUnreadable = 5 };

struct ChildOutcome {
    int waitStatus = 0;     ///< as waitpid() gives it
    std::string errors;     ///< its stderr (the first 16 KiB), trimmed
    bool timedOut = false;  ///< killed at the time limit
};

/// Runs `argv` (argv[0] a path) with stderr captured and stdout discarded; SIGKILLs it after `seconds`.
ChildOutcome runChild(const std::vector<std::string>& argv, double seconds);

/// Throws what a reader child's outcome means: LimitExceeded (kChildOverLimits), InvalidArgument
/// (kChildInvalid, or over its time), IoError (kChildUnreadable, or it crashed inside `library`
/// reading `what`); returns on kChildLoads. `reader` names the reader ("VDB"), `library` what it runs.
void throwChildFailure(const ChildOutcome& outcome, const std::string& what, const std::string& reader, const std::string& library,
                       double seconds);

/// The child's side: caps its address space at `mib` MiB (not under ASan/TSan, which reserve
/// terabytes of shadow memory).
void limitChildMemory(double mib);

/// The child's side: runs `read` and returns the exit status its outcome means (the reason on
/// stderr); `what` names the file in the message of a failed allocation.
int childExitStatus(const std::function<void()>& read, const std::string& what, double mib);

}  // namespace volstyle::server

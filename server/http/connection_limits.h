#pragma once
/// \file connection_limits.h
/// What one HTTP connection and one request's head may take (GuardedHttpServer), and why a
/// connection or request is refused before any route sees it.

#include <cstddef>

namespace volstyle::server {

struct ConnectionLimits {
    double headerSeconds = 10;           ///< the allowance of a request's reads before any byte counts
    double minBytesPerSecond = 64 << 10; ///< each byte received extends the allowance by 1/this
    double idleSeconds = 5;              ///< a keep-alive connection waits this long for its next request
    double writeSeconds = 5;             ///< a write that cannot proceed for this long closes the connection
    int maxConnectionsPerClient = 24;
    int maxRequestsPerConnection = 100;
    int listenBacklog = 1024;            ///< connections the kernel holds before accept (Linux caps it at somaxconn)
    size_t maxQueuedConnections = 512;   ///< accepted connections waiting for a worker; beyond: 503
    int retryAfterSeconds = 2;           ///< the Retry-After of a 503 or 429 refusal
    size_t maxHeadBytes = 32 << 10;      ///< request line and headers together (over: 431)
    int maxHeaderCount = 100;            ///< header lines (over: 431)
    size_t maxTargetBytes = 8192;        ///< the request target (over: 414)
};

/// Why a connection or request is refused before any route sees it.
enum class Refusal {
    ClientConnections,  ///< 429: the client holds maxConnectionsPerClient
    Overloaded,         ///< 503: maxQueuedConnections wait for a worker
    MalformedRequest,   ///< 400: the request line or a header line does not parse, or the path is unsafe
    TargetTooLong,      ///< 414
    HeadTooLarge,       ///< 431: too many header lines or bytes
};

}  // namespace volstyle::server

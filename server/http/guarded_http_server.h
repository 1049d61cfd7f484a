#pragma once
/// \file guarded_http_server.h
/// cpp-httplib's Server with the connection handling a public service needs (issue #9).
/// cpp-httplib 0.11.4 times out single reads only (5 s), so a client sending a header byte every
/// 4 s holds a worker thread for hours. This class overrides the library's one per-connection
/// hook, process_and_close_socket, and reads each request through a stream with a deadline:
///
///  - a request's reads get an allowance of `headerSeconds + bytes received / minBytesPerSecond`
///    from its first byte; a client that falls behind is disconnected;
///  - one client address holds at most `maxConnectionsPerClient` connections (the next one is
///    answered 429 with the body `refusal()` returns, and closed);
///  - an idle keep-alive connection is closed after `idleSeconds`, and stopServing() is noticed
///    within kPollSliceMs (the library's is_running() stays true until every worker has returned,
///    so a connection waiting on it held a stopping server for the whole idle time: 5 s);
///  - connections get TCP_NODELAY (small answers otherwise wait for a delayed ACK);
///  - (issue #35) the listen backlog is `listenBacklog`, not the library's 5 (a burst of 100 new
///    connections was reset by the kernel, unanswered and unlogged); connections beyond
///    `maxQueuedConnections` waiting for a worker are answered 503 with Retry-After at once;
///  - (issue #35) each request's head is read ahead (MSG_PEEK) and checked before the library
///    parses it: a malformed request line, an unknown method, a NUL or an encoded '/' in the path,
///    over `maxHeaderCount` headers or `maxHeadBytes` bytes get ONE answer (400, 414 or 431) and
///    the connection closes (the library answered 400 and read the rest of the head as new
///    requests: two or three status lines for one request). The check is request_head.h; the
///    bounded worker queue and the lingering close of refused sockets are shedding_pool.h.

#include <httplib.h>

#include <atomic>
#include <functional>
#include <map>
#include <mutex>
#include <string>

#include "server/http/connection_limits.h"

namespace volstyle::server {

class GuardedHttpServer : public httplib::Server {
public:
    explicit GuardedHttpServer(ConnectionLimits limits = {});
    ~GuardedHttpServer() override;
    const ConnectionLimits& connectionLimits() const { return m_limits; }
    /// The JSON body of a refusal (the SPEC's error body; `detail` says what was wrong), and the
    /// place to log it: refused connections never reach the library's logger.
    std::function<std::string(Refusal why, const std::string& client, const std::string& detail)> refusal;

    /// bind_to_port (port 0: bind_to_any_port) with the listen backlog raised to listenBacklog;
    /// the port, or -1 when the address cannot be bound.
    int bindWithBacklog(const std::string& host, int port);
    /// Workers serving connections (an open event stream holds one).
    void setWorkerThreads(size_t threads);

    static constexpr int kPollSliceMs = 100;

    /// stop(), and every connection's wait ends within kPollSliceMs (use it rather than stop()).
    void stopServing();
    /// Running and not stopping: what waits on a connection check.
    bool serving() const { return is_running() && !m_stopping; }

private:
    bool process_and_close_socket(socket_t sock) override;
    /// Counts a connection of `client`; false if it holds its limit already.
    bool admit(const std::string& client);
    void leave(const std::string& client);
    /// Sends one refusal with `Connection: close` (best effort, never blocking).
    void refuse(socket_t sock, const std::string& client, Refusal why, const std::string& detail);
    /// Waits up to idleSeconds for the next request's first byte (false: idle, closed or stopping).
    bool awaitRequest(socket_t sock) const;

    ConnectionLimits m_limits;
    std::mutex m_mutex;
    std::map<std::string, int> m_open;  ///< connections by client address
    socket_t m_listenSocket = INVALID_SOCKET;
    std::atomic<bool> m_stopping{false};
};

}  // namespace volstyle::server

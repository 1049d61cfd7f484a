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
///  - an idle keep-alive connection is closed after `idleSeconds`, and stop() is noticed within
///    kPollSliceMs;
///  - connections get TCP_NODELAY (small answers otherwise wait for a delayed ACK).

#include <httplib.h>

#include <functional>
#include <map>
#include <mutex>
#include <string>

namespace volstyle::server {

struct ConnectionLimits {
    double headerSeconds = 10;           ///< the allowance of a request's reads before any byte counts
    double minBytesPerSecond = 64 << 10; ///< each byte received extends the allowance by 1/this
    double idleSeconds = 5;              ///< a keep-alive connection waits this long for its next request
    double writeSeconds = 5;             ///< a write that cannot proceed for this long closes the connection
    int maxConnectionsPerClient = 24;
    int maxRequestsPerConnection = 100;
};

class GuardedHttpServer : public httplib::Server {
public:
    explicit GuardedHttpServer(ConnectionLimits limits = {}) : m_limits(limits) {}
    const ConnectionLimits& connectionLimits() const { return m_limits; }
    /// The JSON body of the 429 sent to a client over its connection limit.
    std::function<std::string(const std::string& client)> refusal;

    static constexpr int kPollSliceMs = 100;

private:
    bool process_and_close_socket(socket_t sock) override;
    /// Counts a connection of `client`; false if it holds its limit already.
    bool admit(const std::string& client);
    void leave(const std::string& client);
    void refuse(socket_t sock, const std::string& client);
    /// Waits up to idleSeconds for the next request's first byte (false: idle, closed or stopping).
    bool awaitRequest(socket_t sock) const;

    ConnectionLimits m_limits;
    std::mutex m_mutex;
    std::map<std::string, int> m_open;  ///< connections by client address
};

}  // namespace volstyle::server

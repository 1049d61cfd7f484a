#include "server/http/guarded_http_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>

#include "server/http/request_head.h"
#include "server/http/shedding_pool.h"

namespace volstyle::server {
namespace {

using SteadyClock = std::chrono::steady_clock;

double secondsSince(SteadyClock::time_point t) {
    return std::chrono::duration<double>(SteadyClock::now() - t).count();
}

/// The numeric address and port of a socket's peer (or its own end).
void socketAddress(socket_t sock, bool peer, std::string& ip, int& port) {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    ip.clear();
    port = -1;
    if ((peer ? ::getpeername(sock, reinterpret_cast<sockaddr*>(&addr), &len)
              : ::getsockname(sock, reinterpret_cast<sockaddr*>(&addr), &len)) != 0)
        return;
    char text[INET6_ADDRSTRLEN] = {};
    if (addr.ss_family == AF_INET) {
        auto* a = reinterpret_cast<sockaddr_in*>(&addr);
        ::inet_ntop(AF_INET, &a->sin_addr, text, sizeof text);
        port = ntohs(a->sin_port);
    } else if (addr.ss_family == AF_INET6) {
        auto* a = reinterpret_cast<sockaddr_in6*>(&addr);
        ::inet_ntop(AF_INET6, &a->sin6_addr, text, sizeof text);
        port = ntohs(a->sin6_port);
    }
    ip = text;
}

/// Polls `sock` for `events` in slices, until ready, `seconds` pass, or `stillWanted` says stop.
/// Returns the revents (0 on time-out or stop).
template <typename StillWanted>
short pollSliced(socket_t sock, short events, double seconds, StillWanted stillWanted) {
    const auto start = SteadyClock::now();
    for (;;) {
        const double left = seconds - secondsSince(start);
        if (left <= 0 || !stillWanted()) return 0;
        pollfd p{sock, events, 0};
        const int ms = int(std::min<double>(GuardedHttpServer::kPollSliceMs, std::ceil(left * 1000)));
        const int n = ::poll(&p, 1, std::max(ms, 1));
        if (n > 0) return p.revents;
        if (n < 0 && errno != EINTR) return POLLERR;
    }
}

/// One request's stream: reads stop at the request's deadline, which moves with the bytes read.
class DeadlineStream final : public httplib::Stream {
public:
    DeadlineStream(socket_t sock, const ConnectionLimits& limits, const GuardedHttpServer& server)
        : m_sock(sock), m_limits(limits), m_server(server), m_start(SteadyClock::now()) {}

    bool is_readable() const override { return waitFor(POLLIN, allowanceLeft()); }
    bool is_writable() const override { return waitFor(POLLOUT, m_limits.writeSeconds); }

    ssize_t read(char* ptr, size_t size) override {
        if (!is_readable()) return -1;  // past the allowance, stopping, or closed: drop the client
        ssize_t n;
        do n = ::recv(m_sock, ptr, size, 0);
        while (n < 0 && errno == EINTR);
        if (n > 0) m_received += size_t(n);
        return n;
    }
    ssize_t write(const char* ptr, size_t size) override {
        if (!is_writable()) return -1;
        ssize_t n;
        do n = ::send(m_sock, ptr, size, MSG_NOSIGNAL);
        while (n < 0 && errno == EINTR);
        return n;
    }
    void get_remote_ip_and_port(std::string& ip, int& port) const override { socketAddress(m_sock, true, ip, port); }
    void get_local_ip_and_port(std::string& ip, int& port) const override { socketAddress(m_sock, false, ip, port); }
    socket_t socket() const override { return m_sock; }

private:
    double allowanceLeft() const {
        const double allowance = m_limits.headerSeconds + double(m_received) / m_limits.minBytesPerSecond;
        return allowance - secondsSince(m_start);
    }
    bool waitFor(short events, double seconds) const {
        // is_running(), not serving(): a reply already being written finishes as the server stops.
        const short r = pollSliced(m_sock, events, seconds, [this] { return m_server.is_running(); });
        return (r & events) != 0;
    }

    socket_t m_sock;
    const ConnectionLimits& m_limits;
    const GuardedHttpServer& m_server;
    SteadyClock::time_point m_start;
    size_t m_received = 0;
};

void closeSocket(socket_t sock) {
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
}

const char* reasonPhrase(int status) {
    switch (status) {
        case 400: return "Bad Request";
        case 414: return "URI Too Long";
        case 429: return "Too Many Requests";
        case 431: return "Request Header Fields Too Large";
        default: return "Service Unavailable";
    }
}

int statusOf(Refusal why) {
    switch (why) {
        case Refusal::ClientConnections: return 429;
        case Refusal::Overloaded: return 503;
        case Refusal::MalformedRequest: return 400;
        case Refusal::TargetTooLong: return 414;
        case Refusal::HeadTooLarge: return 431;
    }
    return 400;
}

/// Reads ahead (without consuming) until the request's head ends, `maxBytes` are waiting, the
/// client closes or `seconds` pass. `complete`: the blank line was seen (the head is returned
/// with it); else the bytes seen so far (empty: nothing came).
std::string peekHead(socket_t sock, size_t maxBytes, double seconds, const GuardedHttpServer& server, bool& complete) {
    complete = false;
    std::string buf(maxBytes + 1, '\0');
    const auto start = SteadyClock::now();
    ssize_t seen = -1;
    for (;;) {
        const ssize_t n = ::recv(sock, buf.data(), buf.size(), MSG_PEEK | MSG_DONTWAIT);
        if (n == 0) return {};  // closed
        if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return {};
        if (n > 0) {
            const std::string_view view(buf.data(), size_t(n));
            const size_t end = view.find("\r\n\r\n");
            if (end != std::string_view::npos) {
                complete = true;
                buf.resize(end + 4);
                return buf;
            }
            if (size_t(n) > maxBytes) {
                buf.resize(size_t(n));
                return buf;
            }
        }
        if (secondsSince(start) > seconds || !server.serving()) {
            buf.resize(size_t(std::max<ssize_t>(n, 0)));
            return buf;
        }
        if (n == seen) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // more bytes are on their way
        else pollSliced(sock, POLLIN, 0.05, [&server] { return server.serving(); });
        seen = n;
    }
}

}  // namespace

GuardedHttpServer::GuardedHttpServer(ConnectionLimits limits) : m_limits(limits) {
    setWorkerThreads(8);
}

GuardedHttpServer::~GuardedHttpServer() = default;

void GuardedHttpServer::setWorkerThreads(size_t threads) {
    new_task_queue = [threads, queued = m_limits.maxQueuedConnections] { return new SheddingPool(threads, queued); };
}

int GuardedHttpServer::bindWithBacklog(const std::string& host, int port) {
    set_socket_options([this](socket_t sock) {
        httplib::default_socket_options(sock);
        m_listenSocket = sock;
    });
    const int bound = port == 0 ? bind_to_any_port(host) : (bind_to_port(host, port) ? port : -1);
    // The library listens with a backlog of 5; listening again on the bound socket raises it.
    if (bound > 0 && m_listenSocket != INVALID_SOCKET) ::listen(m_listenSocket, m_limits.listenBacklog);
    return bound;
}

void GuardedHttpServer::stopServing() {
    m_stopping = true;
    stop();
}

bool GuardedHttpServer::admit(const std::string& client) {
    std::lock_guard lock(m_mutex);
    int& n = m_open[client];
    if (n >= m_limits.maxConnectionsPerClient) {
        if (n == 0) m_open.erase(client);
        return false;
    }
    ++n;
    return true;
}

void GuardedHttpServer::leave(const std::string& client) {
    std::lock_guard lock(m_mutex);
    if (--m_open[client] <= 0) m_open.erase(client);
}

void GuardedHttpServer::refuse(socket_t sock, const std::string& client, Refusal why, const std::string& detail) {
    const int status = statusOf(why);
    const std::string body = refusal ? refusal(why, client, detail) : std::string("{}");
    std::string head = "HTTP/1.1 " + std::to_string(status) + " " + reasonPhrase(status) +
                       "\r\nContent-Type: application/json\r\nConnection: close\r\n";
    if (status == 429 || status == 503) head += "Retry-After: " + std::to_string(m_limits.retryAfterSeconds) + "\r\n";
    const std::string answer = head + "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body;
    // Never blocking: a small answer fits the socket's send buffer.
    ::send(sock, answer.data(), answer.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    closeAfterAnswer(sock);
}

bool GuardedHttpServer::awaitRequest(socket_t sock) const {
    const short r = pollSliced(sock, POLLIN, m_limits.idleSeconds, [this] { return serving(); });
    return (r & POLLIN) != 0;
}

bool GuardedHttpServer::process_and_close_socket(socket_t sock) {
    std::string client;
    int port = 0;
    socketAddress(sock, true, client, port);
    if (SheddingPool::shedNow()) {
        refuse(sock, client, Refusal::Overloaded,
               std::to_string(m_limits.maxQueuedConnections) + " connections are waiting for a worker");
        return false;
    }
    if (!admit(client)) {
        refuse(sock, client, Refusal::ClientConnections, "");
        return false;
    }
    const int one = 1;
    ::setsockopt(sock, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);

    bool ok = true, refused = false;
    for (int served = 0; served < m_limits.maxRequestsPerConnection && ok; ++served) {
        if (!awaitRequest(sock)) break;  // idle, closed by the client, or the server is stopping
        bool complete = false;
        const std::string head = peekHead(sock, m_limits.maxHeadBytes, m_limits.headerSeconds, *this, complete);
        if (head.empty()) break;  // closed, or nothing within the allowance
        Refusal why = Refusal::MalformedRequest;
        std::string problem;
        if (complete) problem = checkRequestHead(head, m_limits, why);
        else if (head.size() > m_limits.maxHeadBytes) {
            const size_t lineEnd = head.find("\r\n");
            if (lineEnd == std::string::npos || lineEnd > m_limits.maxTargetBytes + 32) {
                why = Refusal::TargetTooLong;
                problem = "the request line is over " + std::to_string(m_limits.maxTargetBytes) + " bytes (the limit)";
            } else {
                why = Refusal::HeadTooLarge;
                problem = "the request's head is over " + std::to_string(m_limits.maxHeadBytes) + " bytes (the limit)";
            }
        } else break;  // the head did not arrive within the allowance: drop the client, as before
        if (!problem.empty()) {
            refuse(sock, client, why, problem);
            refused = true;
            ok = false;
            break;
        }
        DeadlineStream stream(sock, m_limits, *this);
        bool closed = false;
        const bool last = served + 1 == m_limits.maxRequestsPerConnection || !serving();
        ok = process_request(stream, last, closed, nullptr) && !closed;
    }
    if (!refused) closeSocket(sock);
    leave(client);
    return ok;
}

}  // namespace volstyle::server

#include "server/guarded_http_server.h"

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
    DeadlineStream(socket_t sock, const ConnectionLimits& limits, const httplib::Server& server)
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
        const short r = pollSliced(m_sock, events, seconds, [this] { return m_server.is_running(); });
        return (r & events) != 0;
    }

    socket_t m_sock;
    const ConnectionLimits& m_limits;
    const httplib::Server& m_server;
    SteadyClock::time_point m_start;
    size_t m_received = 0;
};

void closeSocket(socket_t sock) {
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
}

thread_local bool t_shedding = false;  ///< this connection arrived over the queue limit

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

/// A refused connection is closed only once the client had time to read the answer: closing a
/// socket with unread request bytes sends a reset, and the client may lose the answer with it.
/// One thread reads and discards what such sockets still receive, closing each at end of input
/// or after kLingerSeconds.
class Lingerer {
public:
    ~Lingerer() {
        {
            std::lock_guard lock(m_mutex);
            m_stop = true;
        }
        m_wake.notify_all();
        if (m_thread.joinable()) m_thread.join();
        for (const auto& e : m_sockets) ::close(e.sock);
    }
    void add(socket_t sock) {
        ::shutdown(sock, SHUT_WR);  // the answer is complete: the client sees end of input
        std::lock_guard lock(m_mutex);
        if (m_stop || m_sockets.size() >= kMaxLingering) {
            ::close(sock);
            return;
        }
        m_sockets.push_back({sock, SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(
                                                            std::chrono::duration<double>(kLingerSeconds))});
        if (!m_thread.joinable()) m_thread = std::thread([this] { run(); });
        m_wake.notify_one();
    }

private:
    static constexpr double kLingerSeconds = 2;
    static constexpr size_t kMaxLingering = 1024;
    struct Entry {
        socket_t sock;
        SteadyClock::time_point deadline;
    };
    void run() {
        std::array<char, 16384> sink{};
        std::unique_lock lock(m_mutex);
        while (!m_stop) {
            if (m_sockets.empty()) {
                m_wake.wait(lock, [this] { return m_stop || !m_sockets.empty(); });
                continue;
            }
            std::vector<pollfd> polls;
            for (const auto& e : m_sockets) polls.push_back({e.sock, POLLIN, 0});
            lock.unlock();
            ::poll(polls.data(), polls.size(), 50);
            std::vector<socket_t> done;
            const auto now = SteadyClock::now();
            for (const auto& p : polls) {
                bool finished = false;
                if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
                    const ssize_t n = ::recv(p.fd, sink.data(), sink.size(), MSG_DONTWAIT);
                    finished = n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR);
                }
                if (finished) done.push_back(p.fd);
            }
            lock.lock();
            std::erase_if(m_sockets, [&](const Entry& e) {
                if (e.deadline > now && std::find(done.begin(), done.end(), e.sock) == done.end()) return false;
                ::close(e.sock);
                return true;
            });
        }
    }
    std::mutex m_mutex;
    std::condition_variable m_wake;
    std::vector<Entry> m_sockets;
    bool m_stop = false;
    std::thread m_thread;
};

Lingerer& lingerer() {
    static Lingerer l;
    return l;
}

/// Reads ahead (without consuming) until the request's head ends, `maxBytes` are waiting, the
/// client closes or `seconds` pass. `complete`: the blank line was seen (the head is returned
/// with it); else the bytes seen so far (empty: nothing came).
std::string peekHead(socket_t sock, size_t maxBytes, double seconds, const httplib::Server& server, bool& complete) {
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
        if (secondsSince(start) > seconds || !server.is_running()) {
            buf.resize(size_t(std::max<ssize_t>(n, 0)));
            return buf;
        }
        if (n == seen) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // more bytes are on their way
        else pollSliced(sock, POLLIN, 0.05, [&server] { return server.is_running(); });
        seen = n;
    }
}

bool isTokenChar(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("!#$%&'*+-.^_`|~", c) != nullptr;
}

/// `text` cut to 60 characters with control and non-ASCII bytes as '?', for messages.
std::string printable(std::string_view text) {
    std::string out;
    for (char c : text.substr(0, 60)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
    return text.size() > 60 ? out + "…" : out;
}

}  // namespace

std::string checkRequestHead(const std::string& head, const ConnectionLimits& limits, Refusal& why) {
    if (head.size() > limits.maxHeadBytes) {
        why = Refusal::HeadTooLarge;
        return "the request's head is over " + std::to_string(limits.maxHeadBytes) + " bytes (the limit)";
    }
    why = Refusal::MalformedRequest;
    const size_t lineEnd = head.find("\r\n");
    const std::string_view line = std::string_view(head).substr(0, lineEnd);
    const size_t sp1 = line.find(' '), sp2 = sp1 == std::string_view::npos ? sp1 : line.find(' ', sp1 + 1);
    if (sp2 == std::string_view::npos || line.find(' ', sp2 + 1) != std::string_view::npos)
        return "the request line '" + printable(line) + "' is not 'METHOD /path HTTP/1.1'";
    const std::string_view method = line.substr(0, sp1), target = line.substr(sp1 + 1, sp2 - sp1 - 1),
                           version = line.substr(sp2 + 1);
    static const char* const kMethods[] = {"GET", "HEAD", "POST", "PUT", "DELETE", "OPTIONS", "PATCH"};
    if (std::find(std::begin(kMethods), std::end(kMethods), method) == std::end(kMethods))
        return "the method '" + printable(method) + "' is not one this API serves (GET, HEAD, POST, PUT, DELETE, OPTIONS, PATCH)";
    if (version != "HTTP/1.1" && version != "HTTP/1.0") return "the protocol '" + printable(version) + "' is not HTTP/1.1 or HTTP/1.0";
    if (target.size() > limits.maxTargetBytes) {
        why = Refusal::TargetTooLong;
        return "the request target is " + std::to_string(target.size()) + " bytes, over the limit of " +
               std::to_string(limits.maxTargetBytes);
    }
    if (target.empty() || target[0] != '/') return "the request target '" + printable(target) + "' does not start with '/'";
    for (char c : target)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return "the request target holds a control character";
    std::string path(target.substr(0, target.find('?')));
    for (char& c : path) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (path.find("%00") != std::string::npos) return "the path holds an encoded NUL (%00)";
    if (path.find("%2f") != std::string::npos || path.find("%5c") != std::string::npos)
        return "the path holds an encoded '/' or '\\' (%2F, %5C): no id or file name holds one";
    int headers = 0;
    for (size_t at = lineEnd + 2; at < head.size();) {
        const size_t end = head.find("\r\n", at);
        if (end == std::string::npos || end == at) break;  // the blank line ends the head
        const std::string_view h = std::string_view(head).substr(at, end - at);
        const size_t colon = h.find(':');
        if (colon == std::string_view::npos || colon == 0 ||
            !std::all_of(h.begin(), h.begin() + long(colon), isTokenChar))
            return "the header line '" + printable(h) + "' is not 'Name: value'";
        if (++headers > limits.maxHeaderCount) {
            why = Refusal::HeadTooLarge;
            return "the request has over " + std::to_string(limits.maxHeaderCount) + " headers (the limit)";
        }
        at = end + 2;
    }
    return {};
}

/// httplib's TaskQueue with a bound: a connection that finds `maxQueued` others waiting for a
/// worker is answered at once, on the accepting thread (a 503, see process_and_close_socket).
class GuardedHttpServer::SheddingPool final : public httplib::TaskQueue {
public:
    SheddingPool(size_t threads, size_t maxQueued) : m_maxQueued(maxQueued) {
        for (size_t i = 0; i < threads; ++i) m_workers.emplace_back([this] { work(); });
    }
    void enqueue(std::function<void()> fn) override {
        {
            std::lock_guard lock(m_mutex);
            if (m_jobs.size() < m_maxQueued) {
                m_jobs.push_back(std::move(fn));
                m_wake.notify_one();
                return;
            }
        }
        t_shedding = true;
        fn();
        t_shedding = false;
    }
    void shutdown() override {
        {
            std::lock_guard lock(m_mutex);
            m_stop = true;
        }
        m_wake.notify_all();
        for (auto& t : m_workers) t.join();
    }

private:
    void work() {
        for (;;) {
            std::function<void()> fn;
            {
                std::unique_lock lock(m_mutex);
                m_wake.wait(lock, [this] { return m_stop || !m_jobs.empty(); });
                if (m_jobs.empty()) return;  // stopping, and nothing is left
                fn = std::move(m_jobs.front());
                m_jobs.pop_front();
            }
            fn();
        }
    }
    size_t m_maxQueued;
    std::mutex m_mutex;
    std::condition_variable m_wake;
    std::deque<std::function<void()>> m_jobs;
    std::vector<std::thread> m_workers;
    bool m_stop = false;
};

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
    lingerer().add(sock);
}

bool GuardedHttpServer::awaitRequest(socket_t sock) const {
    const short r = pollSliced(sock, POLLIN, m_limits.idleSeconds, [this] { return is_running(); });
    return (r & POLLIN) != 0;
}

bool GuardedHttpServer::process_and_close_socket(socket_t sock) {
    std::string client;
    int port = 0;
    socketAddress(sock, true, client, port);
    if (t_shedding) {
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
        const bool last = served + 1 == m_limits.maxRequestsPerConnection || !is_running();
        ok = process_request(stream, last, closed, nullptr) && !closed;
    }
    if (!refused) closeSocket(sock);
    leave(client);
    return ok;
}

}  // namespace volstyle::server

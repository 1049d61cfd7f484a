// The HTTP door (server/http/guarded_http_server.h, issue #35): a request's head is checked before
// cpp-httplib parses it (one answer per malformed request, then the connection closes), the
// listen backlog holds a burst, and connections over the worker queue are answered 503 at once.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>
#include <vector>

#include "server/http/guarded_http_server.h"
#include "server/http/request_head.h"

using namespace volstyle::server;

namespace {

std::string check(const std::string& head, Refusal& why, ConnectionLimits limits = {}) {
    return checkRequestHead(head, limits, why);
}

/// Sends `request` on a new connection to 127.0.0.1:port and reads until the server closes.
std::string talk(int port, const std::string& request) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        ::close(fd);
        return "<no connection>";
    }
    ::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
    std::string out;
    std::array<char, 4096> buf{};
    for (ssize_t n; (n = ::recv(fd, buf.data(), buf.size(), 0)) > 0;) out.append(buf.data(), size_t(n));
    ::close(fd);
    return out;
}

int statusLines(const std::string& answer) {
    int n = 0;
    for (size_t at = 0; (at = answer.find("HTTP/1.1 ", at)) != std::string::npos; ++at) ++n;
    return n;
}

/// A GuardedHttpServer on a free port, serving in a thread until destroyed.
struct Running {
    GuardedHttpServer http;
    int port = 0;
    std::thread thread;
    explicit Running(ConnectionLimits limits, size_t workers) : http(limits) {
        http.setWorkerThreads(workers);
        http.refusal = [](Refusal why, const std::string&, const std::string& detail) {
            return std::string("{\"error\":{\"code\":\"") + (why == Refusal::Overloaded ? "overloaded" : "refused") + "\",\"message\":\"" +
                   detail + "\"}}";
        };
        http.Get("/slow", [](const httplib::Request&, httplib::Response& res) {
            std::this_thread::sleep_for(std::chrono::milliseconds(1500));
            res.set_content("done", "text/plain");
        });
        http.Get("/fast", [](const httplib::Request&, httplib::Response& res) { res.set_content("ok", "text/plain"); });
        port = http.bindWithBacklog("127.0.0.1", 0);
        thread = std::thread([this] { http.listen_after_bind(); });
        while (!http.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ~Running() {
        http.stop();
        thread.join();
    }
};

}  // namespace

TEST(RequestHead, WellFormedHeadsPass) {
    Refusal why;
    EXPECT_EQ(check("GET /api/v1/health HTTP/1.1\r\nHost: x\r\n\r\n", why), "");
    EXPECT_EQ(check("PUT /api/v1/sessions/ab/frames/3?x=%2F HTTP/1.0\r\nContent-Length: 3\r\nX-A: b:c\r\n\r\n", why), "")
        << "an encoded '/' in the query is data";
}

TEST(RequestHead, MalformedHeadsAreNamed) {
    Refusal why;
    const std::pair<const char*, const char*> cases[] = {
        {"FOO /api/v1/health HTTP/1.1\r\nHost: x\r\n\r\n", "method 'FOO'"},
        {"\x01\x02 garbage\r\nHost: x\r\n\r\n", "is not 'METHOD /path HTTP/1.1'"},
        {"GET /a HTTP/2.0\r\n\r\n", "protocol 'HTTP/2.0'"},
        {"GET a HTTP/1.1\r\n\r\n", "does not start with '/'"},
        {"GET /index.html%00.png HTTP/1.1\r\n\r\n", "encoded NUL"},
        {"GET /api/v1/sessions/ab%2Fcd HTTP/1.1\r\n\r\n", "encoded '/'"},
        {"GET /a HTTP/1.1\r\nno colon here\r\n\r\n", "is not 'Name: value'"},
        {"GET /a HTTP/1.1\r\n: empty name\r\n\r\n", "is not 'Name: value'"},
    };
    for (const auto& [head, expected] : cases) {
        const std::string problem = check(head, why);
        EXPECT_NE(problem.find(expected), std::string::npos) << head << " -> " << problem;
        EXPECT_EQ(why, Refusal::MalformedRequest) << head;
    }
}

TEST(RequestHead, HeaderCountAndSizeAndTargetLengthAreLimited) {
    Refusal why;
    std::string head = "GET /a HTTP/1.1\r\n";
    for (int i = 0; i < 100; ++i) head += "X-" + std::to_string(i) + ": y\r\n";
    EXPECT_EQ(check(head + "\r\n", why), "") << "100 headers: the limit";
    EXPECT_NE(check(head + "X-100: y\r\n\r\n", why).find("over 100 headers"), std::string::npos);
    EXPECT_EQ(why, Refusal::HeadTooLarge);
    EXPECT_NE(check("GET /a HTTP/1.1\r\nX: " + std::string(40000, 'a') + "\r\n\r\n", why).find("over 32768 bytes"), std::string::npos);
    EXPECT_EQ(why, Refusal::HeadTooLarge);
    EXPECT_NE(check("GET /" + std::string(9000, 'a') + " HTTP/1.1\r\n\r\n", why).find("over the limit of 8192"), std::string::npos);
    EXPECT_EQ(why, Refusal::TargetTooLong);
}

TEST(GuardedHttpServer, AMalformedRequestGetsOneAnswerAndTheConnectionCloses) {
    Running server({}, 2);
    // The rest of the head once read as two more requests: three status lines.
    const std::string answer = talk(server.port, "FOO /fast HTTP/1.1\r\nHost: x\r\nA: b\r\nB: c\r\n\r\n");
    EXPECT_EQ(statusLines(answer), 1) << answer;
    EXPECT_EQ(answer.rfind("HTTP/1.1 400 Bad Request\r\n", 0), 0u) << answer;
    EXPECT_NE(answer.find("Connection: close"), std::string::npos);
    EXPECT_NE(answer.find("method 'FOO'"), std::string::npos) << "the refusal's body";
    std::string many = "GET /fast HTTP/1.1\r\n";
    for (int i = 0; i < 5000; ++i) many += "X-" + std::to_string(i) + ": y\r\n";
    const std::string big = talk(server.port, many + "\r\n");
    EXPECT_EQ(statusLines(big), 1) << big.substr(0, 200);
    EXPECT_EQ(big.rfind("HTTP/1.1 431 ", 0), 0u) << big.substr(0, 200);
    // Good requests on one connection are still served one after the other.
    const std::string two = talk(server.port, "GET /fast HTTP/1.1\r\nHost: x\r\n\r\nGET /fast HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
    EXPECT_EQ(statusLines(two), 2) << two;
}

TEST(GuardedHttpServer, TheListenBacklogHoldsABurst) {
    Running server({}, 2);
    // ss shows a listening socket's backlog as its Send-Q; cpp-httplib's own is 5.
    std::unique_ptr<FILE, int (*)(FILE*)> ss(::popen(("ss -ltnH 'sport = :" + std::to_string(server.port) + "'").c_str(), "r"), ::pclose);
    ASSERT_TRUE(ss) << "ss (iproute2) is installed by scripts/install_deps.sh";
    char line[512] = {};
    ASSERT_TRUE(std::fgets(line, sizeof line, ss.get())) << "ss found no listening socket on port " << server.port;
    char state[32];
    unsigned recvQ = 0, sendQ = 0;
    ASSERT_EQ(std::sscanf(line, "%31s %u %u", state, &recvQ, &sendQ), 3) << line;
    EXPECT_GE(sendQ, 1024u) << line;
}

TEST(GuardedHttpServer, ConnectionsOverTheQueueAreAnswered503WithRetryAfter) {
    ConnectionLimits limits;
    limits.maxQueuedConnections = 1;
    Running server(limits, 1);
    std::vector<std::string> answers(5);
    std::vector<std::thread> clients;
    for (size_t i = 0; i < answers.size(); ++i) {
        clients.emplace_back([&, i] { answers[i] = talk(server.port, "GET /slow HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"); });
        std::this_thread::sleep_for(std::chrono::milliseconds(50));  // in order: the first is being served, the second waits
    }
    for (auto& t : clients) t.join();
    int ok = 0, shed = 0;
    for (const auto& a : answers) {
        EXPECT_EQ(statusLines(a), 1) << "every connection gets one answer: " << a;
        if (a.rfind("HTTP/1.1 200 ", 0) == 0) ++ok;
        if (a.rfind("HTTP/1.1 503 Service Unavailable\r\n", 0) == 0) {
            ++shed;
            EXPECT_NE(a.find("Retry-After: 2\r\n"), std::string::npos) << a;
            EXPECT_NE(a.find("\"code\":\"overloaded\""), std::string::npos) << a;
        }
    }
    EXPECT_EQ(ok, 2) << "one served, one waiting in the queue of 1";
    EXPECT_EQ(shed, 3);
}

#include "server/http/shedding_pool.h"

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>

namespace volstyle::server {
namespace {

using SteadyClock = std::chrono::steady_clock;

thread_local bool t_shedding = false;  ///< this connection arrived over the queue limit

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

}  // namespace

SheddingPool::SheddingPool(size_t threads, size_t maxQueued) : m_maxQueued(maxQueued) {
    for (size_t i = 0; i < threads; ++i) m_workers.emplace_back([this] { work(); });
}

void SheddingPool::enqueue(std::function<void()> fn) {
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

void SheddingPool::shutdown() {
    {
        std::lock_guard lock(m_mutex);
        m_stop = true;
    }
    m_wake.notify_all();
    for (auto& t : m_workers) t.join();
}

bool SheddingPool::shedNow() { return t_shedding; }

void SheddingPool::work() {
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

void closeAfterAnswer(socket_t sock) { lingerer().add(sock); }

}  // namespace volstyle::server

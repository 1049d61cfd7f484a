#pragma once
/// \file shedding_pool.h
/// The HTTP workers with a bounded queue, and the lingering close of refused connections
/// (issue #35). cpp-httplib's ThreadPool queues without bound: a burst waits for ever. A
/// connection that finds `maxQueued` others waiting is run at once on the accepting thread with
/// shedNow() true, so the server answers it 503 without reading it.

#include <httplib.h>

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace volstyle::server {

class SheddingPool final : public httplib::TaskQueue {
public:
    SheddingPool(size_t threads, size_t maxQueued);
    void enqueue(std::function<void()> fn) override;
    void shutdown() override;
    /// Whether the connection this thread handles now arrived over the queue's bound.
    static bool shedNow();

private:
    void work();
    size_t m_maxQueued;
    std::mutex m_mutex;
    std::condition_variable m_wake;
    std::deque<std::function<void()>> m_jobs;
    std::vector<std::thread> m_workers;
    bool m_stop = false;
};

/// Shuts the socket for writing (the answer is complete) and closes it once the client has read
/// it: after the client's end of input, or 2 s. Closing a socket that holds unread request bytes
/// sends a reset, and the client may lose the answer with it.
void closeAfterAnswer(socket_t sock);

}  // namespace volstyle::server

#pragma once
// A live stream (multipart/x-mixed-replace, issue #40) read on a thread of its own: each part's
// headers and body as they arrive, and waits for a count or a condition. The stylizer's and the
// viewport's stream tests share it.
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace volstyle::test {

struct StreamPart {
    std::map<std::string, std::string> headers;
    std::string body;
    bool isJpeg() const { return headers.count("Content-Type") && headers.at("Content-Type") == "image/jpeg"; }
    uint64_t number(const std::string& header) const { return headers.count(header) ? std::stoull(headers.at(header)) : 0; }
};

class MultipartStream {
public:
    /// Opens GET `path` on 127.0.0.1:`port` and reads until the stream ends (join() waits for it).
    MultipartStream(int port, const std::string& path) : m_client("127.0.0.1", port) {
        m_client.set_read_timeout(120, 0);
        m_thread = std::thread([this, path] {
            m_client.Get(path.c_str(), [this](const httplib::Response& r) { m_contentType = r.get_header_value("Content-Type"); return true; },
                         [this](const char* data, size_t n) { return !m_closing && consume(data, n); });
        });
    }
    /// A test that ended early (a failed assertion) leaves the stream open: it is closed here
    /// rather than waited for (keep-alive parts would hold it open for ever).
    ~MultipartStream() {
        m_closing = true;
        m_client.stop();
        join();
    }
    void join() {
        if (m_thread.joinable()) m_thread.join();
    }
    std::string contentType() const { return m_contentType; }
    std::vector<StreamPart> parts() const {
        std::lock_guard lock(m_mutex);
        return m_parts;
    }
    size_t jpegs() const {
        size_t n = 0;
        for (const auto& p : parts()) n += p.isJpeg();
        return n;
    }
    /// Waits up to `seconds` until `done(parts)` holds; whether it did.
    bool waitUntil(const std::function<bool(const std::vector<StreamPart>&)>& done, double seconds = 60) const {
        const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
        while (!done(parts())) {
            if (std::chrono::steady_clock::now() > until) return false;
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        return true;
    }
    bool waitForJpegs(size_t count, double seconds = 60) const {
        return waitUntil([&](const std::vector<StreamPart>&) { return jpegs() >= count; }, seconds);
    }

private:
    bool consume(const char* data, size_t n) {
        m_buffer.append(data, n);
        for (;;) {  // --boundary CRLF, headers, CRLF CRLF, Content-Length bytes, CRLF
            const size_t head = m_buffer.find("\r\n\r\n");
            if (head == std::string::npos) return true;
            StreamPart p;
            std::istringstream lines(m_buffer.substr(0, head));
            for (std::string line; std::getline(lines, line);) {
                const size_t colon = line.find(':');
                if (!line.empty() && line.back() == '\r') line.pop_back();
                if (colon != std::string::npos) p.headers[line.substr(0, colon)] = line.substr(colon + 2);
            }
            const size_t length = std::stoul(p.headers["Content-Length"]);
            if (m_buffer.size() < head + 4 + length + 2) return true;
            p.body = m_buffer.substr(head + 4, length);
            m_buffer.erase(0, head + 4 + length + 2);
            std::lock_guard lock(m_mutex);
            m_parts.push_back(std::move(p));
        }
    }

    httplib::Client m_client;
    std::atomic<bool> m_closing{false};
    std::thread m_thread;
    std::string m_buffer, m_contentType;
    mutable std::mutex m_mutex;
    std::vector<StreamPart> m_parts;
};

}  // namespace volstyle::test

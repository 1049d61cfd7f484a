#include "server/state/session_store.h"

#include <ctime>

#include <random>

#include "core/base/errors.h"

namespace volstyle::server {

std::string isoNow() {
    std::time_t t = std::time(nullptr);
    std::tm utc{};
    gmtime_r(&t, &utc);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &utc);
    return buf;
}

std::string SessionStore::newId() {
    // 128 bits from the OS's entropy source (std::random_device reads /dev/urandom on Linux).
    static std::mutex m;
    static std::random_device device;
    std::lock_guard lock(m);
    std::string id;
    const char* hex = "0123456789abcdef";
    for (int i = 0; i < 4; ++i) {
        uint32_t r = device();
        for (int k = 0; k < 8; ++k, r >>= 4) id += hex[r & 15];
    }
    return id;
}

protocol::ApiError tooManySessions(size_t max) {
    return protocol::ApiError(protocol::ErrorCode::TooManySessions,
                              "the server holds its limit of " + std::to_string(max) + " sessions; delete one first");
}

std::shared_ptr<Session> SessionStore::add(std::shared_ptr<Session> s) {
    std::lock_guard lock(m_mutex);
    if (m_sessions.size() >= m_max)
        throw tooManySessions(m_max);
    s->id = newId();
    m_sessions[s->id] = s;
    return s;
}

void SessionStore::restore(std::shared_ptr<Session> s) {
    std::lock_guard lock(m_mutex);
    m_sessions[s->id] = std::move(s);
}

std::shared_ptr<Session> SessionStore::find(const std::string& id) const {
    std::lock_guard lock(m_mutex);
    auto it = m_sessions.find(id);
    return it == m_sessions.end() ? nullptr : it->second;
}

std::shared_ptr<Session> SessionStore::remove(const std::string& id) {
    std::lock_guard lock(m_mutex);
    auto it = m_sessions.find(id);
    if (it == m_sessions.end()) return nullptr;
    auto s = it->second;
    m_sessions.erase(it);
    return s;
}

std::vector<std::shared_ptr<Session>> SessionStore::all() const {
    std::lock_guard lock(m_mutex);
    std::vector<std::shared_ptr<Session>> out;
    for (const auto& [id, s] : m_sessions) out.push_back(s);
    return out;
}

size_t SessionStore::size() const {
    std::lock_guard lock(m_mutex);
    return m_sessions.size();
}

SessionView& findView(Session& s, const std::string& id) {
    for (auto& v : s.views.list)
        if (v.id == id) return v;
    throw protocol::ApiError(protocol::ErrorCode::NotFound, "no view '" + id + "' in session '" + s.id + "'");
}


}  // namespace volstyle::server

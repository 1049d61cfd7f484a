#include "server/http/idempotency.h"

#include <algorithm>

#include "protocol/error_code.h"

namespace volstyle::server {

std::optional<KeptAnswer> IdempotencyKeys::claim(const std::string& scope, uint64_t bodyHash) {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(m_mutex);
    forgetOld(now);
    auto it = m_entries.find(scope);
    if (it == m_entries.end()) {
        if (m_entries.size() >= kMaxKeys)
            throw protocol::ApiError(protocol::ErrorCode::Overloaded, "the server holds its limit of idempotency keys; retry later");
        m_entries[scope] = {bodyHash, std::nullopt, now};
        return std::nullopt;
    }
    if (it->second.bodyHash != bodyHash)
        throw protocol::ApiError(protocol::ErrorCode::IdempotencyConflict,
                                 "this Idempotency-Key was used with another body; use a new key for a new request",
                                 {{"Idempotency-Key", "was used with another body"}});
    if (!it->second.answer)
        throw protocol::ApiError(protocol::ErrorCode::Busy, "the request with this Idempotency-Key is still running; retry in a moment");
    return it->second.answer;
}

void IdempotencyKeys::finish(const std::string& scope, KeptAnswer answer) {
    std::lock_guard lock(m_mutex);
    auto it = m_entries.find(scope);
    if (it != m_entries.end()) it->second.answer = std::move(answer);
}

void IdempotencyKeys::abandon(const std::string& scope) {
    std::lock_guard lock(m_mutex);
    m_entries.erase(scope);
}

void IdempotencyKeys::forgetOld(std::chrono::steady_clock::time_point now) {
    for (auto it = m_entries.begin(); it != m_entries.end();)
        it = it->second.answer && now - it->second.when > kLifetime ? m_entries.erase(it) : std::next(it);
}

}  // namespace volstyle::server

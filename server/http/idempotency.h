#pragma once
/// \file idempotency.h
/// `Idempotency-Key` on the POSTs that create sessions or jobs (SPEC §10; the IETF httpapi
/// draft's semantics): the first request with a key runs and its 2xx answer is kept; a retry
/// with the same key, route and body gets that answer again (the same session or job, marked
/// `Idempotent-Replayed: true`); the same key with another body is 422; a retry while the first
/// is still running is 409. Keys live 24 h, at most kMaxKeys at once, in this server's memory
/// (a restart forgets them).

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace volstyle::server {

/// An answer kept for replay.
struct KeptAnswer {
    int status = 0;
    std::string body, contentType, location;
};

class IdempotencyKeys {
public:
    static constexpr size_t kMaxKeys = 10000;
    static constexpr std::chrono::hours kLifetime{24};

    /// Claims `scope` (method, path and key) for a request whose body hashes to `bodyHash`: none
    /// when the request should run (then finish() or abandon() it), or the answer to replay.
    /// Throws ApiError 422 (another body) or 409 (still running).
    std::optional<KeptAnswer> claim(const std::string& scope, uint64_t bodyHash);
    void finish(const std::string& scope, KeptAnswer answer);
    /// The request failed: a retry runs it again.
    void abandon(const std::string& scope);

private:
    struct Entry {
        uint64_t bodyHash = 0;
        std::optional<KeptAnswer> answer;  ///< none while the first request runs
        std::chrono::steady_clock::time_point when;
    };
    void forgetOld(std::chrono::steady_clock::time_point now);

    std::mutex m_mutex;
    std::map<std::string, Entry> m_entries;
};

}  // namespace volstyle::server

#pragma once
/// \file content_hash.h
/// FNV-1a, 64 bits: the stable fingerprint of a body for ETags and for telling a retried request
/// from another one under the same Idempotency-Key (not a defence against forgery).

#include <cstdint>
#include <string_view>

namespace volstyle {

inline uint64_t contentHash(std::string_view bytes) {
    uint64_t h = 0xcbf29ce484222325ull;
    for (unsigned char c : bytes) {
        h ^= c;
        h *= 0x100000001b3ull;
    }
    return h;
}

}  // namespace volstyle

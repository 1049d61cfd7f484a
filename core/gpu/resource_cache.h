#pragma once
/// \file resource_cache.h
/// GPU resources derived from others (light-depth volumes from an extinction grid and a light,
/// environment textures from an image), kept between frames and shared-owned: the cache holds one
/// reference and drops the least recently used once it holds more than its capacity; whoever
/// binds a resource (a render, a solve's projector) holds another, so eviction never frees what
/// is in use. A key must name everything the resource depends on. GL thread only.

#include <cstdint>
#include <memory>
#include <string>
#include <typeindex>
#include <unordered_map>

#include "core/base/errors.h"

namespace volstyle::core {

class ResourceCache {
public:
    explicit ResourceCache(size_t capacity) : m_capacity(capacity) {}

    /// The resource stored under `key`, or nullptr. Marks it recently used.
    template <typename T>
    std::shared_ptr<const T> find(const std::string& key) {
        auto it = m_entries.find(key);
        if (it == m_entries.end()) return nullptr;
        if (it->second.type != std::type_index(typeid(T)))
            throw InternalError("ResourceCache: '" + key + "' holds another type");
        it->second.lastUsed = ++m_clock;
        return std::static_pointer_cast<const T>(it->second.value);
    }

    /// Stores `value` under `key` (replacing any), then evicts beyond the capacity.
    template <typename T>
    std::shared_ptr<const T> insert(const std::string& key, std::shared_ptr<const T> value) {
        m_entries[key] = Entry{value, std::type_index(typeid(T)), ++m_clock};
        evict();
        return value;
    }

    size_t size() const { return m_entries.size(); }
    size_t capacity() const { return m_capacity; }
    void clear() { m_entries.clear(); }

private:
    struct Entry {
        std::shared_ptr<const void> value;
        std::type_index type = std::type_index(typeid(void));
        uint64_t lastUsed = 0;
    };
    void evict();

    size_t m_capacity;
    uint64_t m_clock = 0;
    std::unordered_map<std::string, Entry> m_entries;
};

}  // namespace volstyle::core

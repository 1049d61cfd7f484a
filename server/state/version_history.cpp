#include "server/state/version_history.h"

namespace volstyle::server {

void VersionHistory::add(int n) { m_numbers.insert(n); }

void VersionHistory::retire(int n, core::Volume volume) {
    if (!has(n)) return;
    m_memory[n] = std::make_shared<const core::Volume>(std::move(volume));
    m_recent = n;
    trim();
}

void VersionHistory::markStored(int n, std::uintmax_t bytes) {
    m_stored[n] = bytes;
    trim();
}

std::optional<std::uintmax_t> VersionHistory::storedBytes(int n) const {
    auto it = m_stored.find(n);
    if (it == m_stored.end()) return std::nullopt;
    return it->second;
}

void VersionHistory::markDamaged(int n, const std::string& reason) {
    m_damaged[n] = reason;
    m_stored.erase(n);
    m_memory.erase(n);
}

void VersionHistory::remember(int n, const core::Volume& volume) { retire(n, volume); }

std::optional<std::string> VersionHistory::damage(int n) const {
    auto it = m_damaged.find(n);
    if (it == m_damaged.end()) return std::nullopt;
    return it->second;
}

std::shared_ptr<const core::Volume> VersionHistory::inMemory(int n) const {
    auto it = m_memory.find(n);
    return it == m_memory.end() ? nullptr : it->second;
}

std::vector<int> VersionHistory::unstored() const {
    std::vector<int> out;
    for (int n : m_numbers)
        if (!m_stored.count(n) && !m_damaged.count(n)) out.push_back(n);
    return out;
}

void VersionHistory::trim() {
    std::erase_if(m_memory, [&](const auto& entry) { return entry.first != m_recent && m_stored.count(entry.first); });
}

}  // namespace volstyle::server

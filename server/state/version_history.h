#pragma once
/// \file version_history.h
/// A session's committed volume versions (issue #9: every version stayed in RAM, ~200 MiB per
/// 256³ upload). Every number stays listed, for revert and download; the current version is the
/// session's `volume`; of the older ones, those written to disk leave memory except the most
/// recently used one (the likely next revert). Without a data directory nothing is on disk and
/// every version stays in memory, as before. Versions whose file turned out damaged stay listed
/// with the reason. Guarded by the session's lock.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/volume/volume.h"

namespace volstyle::server {

class VersionHistory {
public:
    /// Lists version `n` (newest so far); its volume is the session's current one.
    void add(int n);
    /// Version `n` stops being current: `volume` is kept in memory if it is not on disk yet, or
    /// as the most recently used older version.
    void retire(int n, core::Volume volume);
    /// Version `n` is on disk as a file of `bytes` (written, or found there on restore): it may
    /// leave memory. The size is checked before the file is read back or sent.
    void markStored(int n, std::uintmax_t bytes);
    std::optional<std::uintmax_t> storedBytes(int n) const;
    /// Version `n`'s file is unreadable: listed as damaged, with the reason, and out of memory.
    void markDamaged(int n, const std::string& reason);
    /// Keeps a copy of `n` (read back from disk) as the most recently used older version.
    void remember(int n, const core::Volume& volume);

    bool has(int n) const { return m_numbers.count(n) != 0; }
    bool isStored(int n) const { return m_stored.count(n) != 0; }
    /// The reason version `n` is damaged, if it is.
    std::optional<std::string> damage(int n) const;
    int newest() const { return m_numbers.empty() ? 0 : *m_numbers.rbegin(); }
    const std::set<int>& numbers() const { return m_numbers; }
    const std::map<int, std::string>& damaged() const { return m_damaged; }
    /// The older version `n` in memory, or null (then read it from disk).
    std::shared_ptr<const core::Volume> inMemory(int n) const;
    /// Versions not on disk yet (persistence writes them).
    std::vector<int> unstored() const;
    size_t inMemoryCount() const { return m_memory.size(); }
    /// Bytes the older versions held in memory take.
    size_t memoryBytes() const {
        size_t n = 0;
        for (const auto& [_, v] : m_memory) n += v->memoryBytes();
        return n;
    }

private:
    /// Drops stored older versions from memory except the most recently used one.
    void trim();

    std::set<int> m_numbers;
    std::map<int, std::uintmax_t> m_stored;  ///< versions on disk, and their files' sizes
    std::map<int, std::string> m_damaged;
    std::map<int, std::shared_ptr<const core::Volume>> m_memory;  ///< older versions held in RAM
    int m_recent = 0;  ///< the most recently used older version
};

}  // namespace volstyle::server

#pragma once
/// \file memory_budget.h
/// What sessions hold in memory, decoded, against a per-session and a server-wide budget (issue
/// #35). An 8.8 KB VDB holding one 256³ tile is 201 MB once dense: uploaded as frame after frame it
/// grew the server by 200 MB a frame until the allocator refused (the 1,000-frame limit allowed
/// ~200 GB). Now each addition — a frame, a volume version, a mesh, a view's image, an environment
/// map — is charged by its decoded size before it is stored, and refused naming the budget, what
/// the session (or the server) holds and the limit: 507 memory_budget past the session's budget
/// (the client must delete something), 503 overloaded with Retry-After past the server's (other
/// sessions may free memory); what is refused or
/// deleted is released. The charge is recounted from the session itself after every change
/// (ServiceContext::saved), so it cannot drift from what is held.

#include <cstddef>
#include <mutex>
#include <string>

namespace volstyle::server {

struct Session;

struct MemoryLimits {
    size_t perSession = size_t(2) << 30;  ///< 2 GiB: a 256³ volume with every grid is 470 MB
    size_t total = size_t(8) << 30;       ///< 8 GiB for all sessions together
};

/// The bytes `s` holds decoded: its volume, the older versions kept in memory, the animation's
/// frames, the views' images, the environment map and the occluder meshes (call with its lock).
size_t decodedBytes(const Session& s);

class MemoryBudget {
public:
    explicit MemoryBudget(MemoryLimits limits) : m_limits(limits) {}
    const MemoryLimits& limits() const { return m_limits; }

    /// Throws ApiError memory_budget (507) when `s` (locked by the caller) growing by `adding`
    /// bytes and shrinking by `freeing` would pass its budget or the server's; `what` names the
    /// addition ("frame 12", "the uploaded volume").
    void check(const Session& s, size_t adding, size_t freeing, const std::string& what) const;
    /// The same for a session being created (it holds nothing yet).
    void checkNew(size_t adding, const std::string& what) const;
    /// Records what `s` (locked) holds now; call after every change.
    void recount(Session& s);
    /// Releases a deleted session's charge.
    void forget(Session& s);
    size_t total() const;

private:
    void checkTotals(size_t sessionNow, size_t sessionCharged, size_t projected, const std::string& what) const;

    MemoryLimits m_limits;
    mutable std::mutex m_mutex;
    size_t m_total = 0;  ///< Σ sessions' charges
};

}  // namespace volstyle::server

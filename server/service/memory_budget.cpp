#include "server/service/memory_budget.h"

#include <fmt/format.h>

#include "protocol/error_code.h"
#include "server/state/session_store.h"

namespace volstyle::server {
namespace {

size_t imageBytes(const core::Image& img) { return img.rgba.size() * sizeof(float); }

std::string mib(size_t bytes) { return fmt::format("{:.0f} MiB", double(bytes) / double(1 << 20)); }

}  // namespace

size_t decodedBytes(const Session& s) {
    size_t n = s.volume.current.memoryBytes() + s.volume.versions.memoryBytes();
    for (const auto& [_, f] : s.frames) n += f.volume.memoryBytes();
    for (const auto& v : s.views.list) {
        if (v.target) n += imageBytes(*v.target);
        if (v.weights) n += imageBytes(*v.weights);
        if (v.background) n += imageBytes(*v.background);
    }
    if (s.light.environmentMap) n += imageBytes(*s.light.environmentMap);
    for (const auto& [_, m] : s.stylizer.meshes)
        if (m.mesh) n += (m.mesh->positions.size() + m.mesh->normals.size()) * sizeof(Vec3) + m.mesh->indices.size() * sizeof(uint32_t);
    if (s.stylizer.transferImage) n += imageBytes(*s.stylizer.transferImage);
    return n;
}

void MemoryBudget::checkTotals(size_t sessionNow, size_t sessionCharged, size_t projected, const std::string& what) const {
    using protocol::ApiError;
    using protocol::ErrorCode;
    if (projected > m_limits.perSession && projected > sessionNow)
        throw ApiError(ErrorCode::OutOfBudget,
                       fmt::format("{} would bring the session's memory to {} (decoded), over its budget of {}; it holds {} now "
                                   "(frames, volume versions, meshes, images): delete some (DELETE …/frames/N, …) or use smaller volumes",
                                   what, mib(projected), mib(m_limits.perSession), mib(sessionNow)));
    std::lock_guard lock(m_mutex);
    const size_t others = m_total - std::min(m_total, sessionCharged);
    if (others + projected > m_limits.total && projected > sessionNow)
        throw ApiError(ErrorCode::Overloaded,  // the server's state, not this client's: 503 with Retry-After
                       fmt::format("{} would bring the server's sessions to {} (decoded), over the server's memory budget of {}; "
                                   "retry later, once other sessions are deleted (volstyle serve --memory-mib)",
                                   what, mib(others + projected), mib(m_limits.total)));
}

void MemoryBudget::check(const Session& s, size_t adding, size_t freeing, const std::string& what) const {
    const size_t now = decodedBytes(s);
    checkTotals(now, s.chargedBytes, now - std::min(now, freeing) + adding, what);
}

void MemoryBudget::checkNew(size_t adding, const std::string& what) const { checkTotals(0, 0, adding, what); }

void MemoryBudget::recount(Session& s) {
    const size_t now = s.removed ? 0 : decodedBytes(s);
    std::lock_guard lock(m_mutex);
    m_total = m_total - std::min(m_total, s.chargedBytes) + now;
    s.chargedBytes = now;
}

void MemoryBudget::forget(Session& s) {
    std::lock_guard lock(m_mutex);
    m_total -= std::min(m_total, s.chargedBytes);
    s.chargedBytes = 0;
}

size_t MemoryBudget::total() const {
    std::lock_guard lock(m_mutex);
    return m_total;
}

}  // namespace volstyle::server

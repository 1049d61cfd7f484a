#include "core/gl/readback_ring.h"

#include <string>

#include "core/base/errors.h"

namespace volstyle::core::gl {
namespace {

/// Persistent and coherent: the mapping lives as long as the buffer, and a fence is all the host
/// needs before reading. Client storage asks the driver for host memory (read by the CPU only).
constexpr GLbitfield kMapping = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;

}  // namespace

ReadbackRing::ReadbackRing(int slots) : m_slots(new Slot[size_t(slots)]), m_count(slots) {}

ReadbackRing::~ReadbackRing() = default;  // deleting a buffer unmaps it

int ReadbackRing::acquire(size_t bytes) {
    for (int i = 0; i < m_count; ++i) {
        Slot& s = m_slots[size_t(i)];
        bool expected = false;
        if (!s.held.compare_exchange_strong(expected, true)) continue;
        if (s.bytes < bytes) {
            s.buffer.reset();
            s.bytes = 0;
            s.mapped = nullptr;
            try {
                s.buffer = createBuffer(bytes, nullptr, kMapping | GL_CLIENT_STORAGE_BIT, "readback-slot-" + std::to_string(i));
                s.mapped = static_cast<const uint8_t*>(glMapNamedBufferRange(s.buffer.id(), 0, GLsizeiptr(bytes), kMapping));
                if (!s.mapped) throw GpuError("a read-back buffer of " + std::to_string(bytes) + " bytes could not be mapped");
            } catch (...) {
                s.buffer.reset();
                s.held = false;
                throw;
            }
            s.bytes = bytes;
        }
        return i;
    }
    throw GpuError("every read-back slot is held (" + std::to_string(m_count) + ")");
}

const Buffer& ReadbackRing::buffer(int slot) const { return m_slots[size_t(slot)].buffer; }

const uint8_t* ReadbackRing::complete(int slot) {
    // Shader writes reach a persistently mapped buffer's host view only after this barrier.
    glMemoryBarrier(GL_CLIENT_MAPPED_BUFFER_BARRIER_BIT);
    Fence fence = Fence::insert();
    if (!fence.wait()) throw GpuError("the GPU did not finish a read-back");
    return m_slots[size_t(slot)].mapped;
}

void ReadbackRing::release(int slot) { m_slots[size_t(slot)].held = false; }

int ReadbackRing::held() const {
    int n = 0;
    for (int i = 0; i < m_count; ++i) n += m_slots[size_t(i)].held ? 1 : 0;
    return n;
}

}  // namespace volstyle::core::gl

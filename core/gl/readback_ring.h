#pragma once
/// \file readback_ring.h
/// Buffers the GPU writes and any thread may read (issue #40: a live frame's read-back overlapped
/// with the next frame). Each slot is a buffer mapped persistently and coherently for reading (the
/// pixel-buffer object of a buffer-to-host read): a kernel writes a slot, complete() fences the
/// commands so far and waits for them on the GL thread, and from then on the slot's bytes are plain
/// host memory. Whoever holds the slot reads (encodes) them on its own thread while the GL thread
/// renders the next frame into another slot, and release() hands it back. Creation, acquire() and
/// complete() run on the GL thread; release() and bytes() on any.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/gl/object.h"

namespace volstyle::core::gl {

class ReadbackRing {
public:
    explicit ReadbackRing(int slots = 2);
    ~ReadbackRing();
    ReadbackRing(const ReadbackRing&) = delete;
    ReadbackRing& operator=(const ReadbackRing&) = delete;

    /// GL thread: a slot nobody holds, at least `bytes` long (made larger when it is not), now
    /// held. Throws GpuError when every slot is held (each holder must release() its slot).
    int acquire(size_t bytes);
    /// The slot's buffer, for a kernel to write (GL thread, while held).
    const Buffer& buffer(int slot) const;
    /// GL thread: makes the kernels' writes visible to the host, fences them and waits; returns
    /// the slot's bytes, readable from any thread until release().
    const uint8_t* complete(int slot);
    /// Any thread: the holder is done with the slot's bytes.
    void release(int slot);
    /// How many slots are held now (tests).
    int held() const;

private:
    struct Slot {
        Buffer buffer;
        size_t bytes = 0;
        const uint8_t* mapped = nullptr;
        std::atomic<bool> held{false};
    };
    std::unique_ptr<Slot[]> m_slots;
    int m_count = 0;
};

}  // namespace volstyle::core::gl

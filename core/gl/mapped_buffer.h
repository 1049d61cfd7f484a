#pragma once
/// \file mapped_buffer.h
/// A buffer's bytes mapped into this process for as long as the object lives
/// (glMapNamedBufferRange, then glUnmapNamedBuffer). The buffer must have been created with the
/// matching GL_MAP_READ_BIT / GL_MAP_WRITE_BIT storage flags. On a CPU rasterizer this is the
/// buffer's own memory: the host reads and writes it without a copy each way. GL thread only.

#include <epoxy/gl.h>

#include <cstddef>

#include "core/gl/object.h"

namespace volstyle::core::gl {

class MappedBuffer {
public:
    /// Maps `bytes` from the start of `buffer` with `access` (GL_MAP_READ_BIT, GL_MAP_WRITE_BIT, …);
    /// throws GpuError when the driver refuses.
    MappedBuffer(const Buffer& buffer, size_t bytes, GLbitfield access);
    ~MappedBuffer();
    MappedBuffer(const MappedBuffer&) = delete;
    MappedBuffer& operator=(const MappedBuffer&) = delete;

    template <typename T>
    T* as() const { return static_cast<T*>(m_data); }

private:
    GLuint m_buffer = 0;
    void* m_data = nullptr;
};

}  // namespace volstyle::core::gl

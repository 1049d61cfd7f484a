#include "core/gl/mapped_buffer.h"

#include <string>

#include "core/base/errors.h"

namespace volstyle::core::gl {

MappedBuffer::MappedBuffer(const Buffer& buffer, size_t bytes, GLbitfield access) : m_buffer(buffer.id()) {
    if (bytes == 0) return;  // nothing to map (GL refuses a zero-length range)
    m_data = glMapNamedBufferRange(m_buffer, 0, GLsizeiptr(bytes), access);
    if (!m_data) throw GpuError("a buffer of " + std::to_string(bytes) + " bytes could not be mapped (GL error " + std::to_string(glGetError()) + ")");
}

MappedBuffer::~MappedBuffer() {
    if (m_data) glUnmapNamedBuffer(m_buffer);
}

}  // namespace volstyle::core::gl

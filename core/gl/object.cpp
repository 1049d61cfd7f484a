// The only place GL object names are created and deleted.

#include "core/gl/object.h"

#include <algorithm>

#include "core/base/errors.h"

namespace volstyle::core::gl {
namespace {

void label(GLenum kind, GLuint id, const std::string& name) {
    if (!name.empty()) glObjectLabel(kind, id, GLsizei(name.size()), name.c_str());
}

}  // namespace

void BufferTraits::destroy(GLuint id) { glDeleteBuffers(1, &id); }
void TextureTraits::destroy(GLuint id) { glDeleteTextures(1, &id); }
void ProgramTraits::destroy(GLuint id) { glDeleteProgram(id); }
void SamplerTraits::destroy(GLuint id) { glDeleteSamplers(1, &id); }
void QueryTraits::destroy(GLuint id) { glDeleteQueries(1, &id); }
void FramebufferTraits::destroy(GLuint id) { glDeleteFramebuffers(1, &id); }
void VertexArrayTraits::destroy(GLuint id) { glDeleteVertexArrays(1, &id); }

Buffer createBuffer(size_t bytes, const void* data, GLbitfield storageFlags, const std::string& name) {
    GLuint id = 0;
    glCreateBuffers(1, &id);
    glNamedBufferStorage(id, GLsizeiptr(bytes), data, storageFlags);
    label(GL_BUFFER, id, name);
    return Buffer(id);
}

void writeBuffer(const Buffer& buffer, size_t offset, size_t bytes, const void* data) {
    const auto* bytesIn = static_cast<const unsigned char*>(data);
    for (size_t done = 0; done < bytes; done += kWriteChunkBytes) {
        const size_t n = std::min(kWriteChunkBytes, bytes - done);
        // Deleted at the end of this iteration: GL keeps it until the copy has read it.
        const Buffer staging = createBuffer(n, bytesIn + done, 0, "upload-staging");
        glCopyNamedBufferSubData(staging.id(), buffer.id(), 0, GLintptr(offset + done), GLsizeiptr(n));
    }
}

Texture createTexture(GLenum target, const std::string& name) {
    GLuint id = 0;
    glCreateTextures(target, 1, &id);
    label(GL_TEXTURE, id, name);
    return Texture(id);
}

Texture createTexture2D(GLenum format, int w, int h, GLenum filter, const std::string& name) {
    Texture t = createTexture(GL_TEXTURE_2D, name);
    glTextureStorage2D(t.id(), 1, format, w, h);
    glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GLint(filter));
    glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GLint(filter));
    glTextureParameteri(t.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

void checkFramebufferComplete(const Framebuffer& fb, const std::string& what) {
    const GLenum status = glCheckNamedFramebufferStatus(fb.id(), GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw GpuError(what + " framebuffer is incomplete (status " + std::to_string(status) + ")");
}

Program createProgram(const std::string& name) {
    GLuint id = glCreateProgram();
    label(GL_PROGRAM, id, name);
    return Program(id);
}

Sampler createSampler(const std::string& name) {
    GLuint id = 0;
    glCreateSamplers(1, &id);
    label(GL_SAMPLER, id, name);
    return Sampler(id);
}

Query createQuery(GLenum target, const std::string& name) {
    GLuint id = 0;
    glCreateQueries(target, 1, &id);
    label(GL_QUERY, id, name);
    return Query(id);
}

Framebuffer createFramebuffer(const std::string& name) {
    GLuint id = 0;
    glCreateFramebuffers(1, &id);
    label(GL_FRAMEBUFFER, id, name);
    return Framebuffer(id);
}

VertexArray createVertexArray(const std::string& name) {
    GLuint id = 0;
    glCreateVertexArrays(1, &id);
    label(GL_VERTEX_ARRAY, id, name);
    return VertexArray(id);
}

Fence::~Fence() {
    if (m_sync) glDeleteSync(m_sync);
}

Fence& Fence::operator=(Fence&& o) noexcept {
    if (this != &o) {
        if (m_sync) glDeleteSync(m_sync);
        m_sync = std::exchange(o.m_sync, nullptr);
    }
    return *this;
}

Fence Fence::insert() {
    Fence f;
    f.m_sync = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    return f;
}

bool Fence::wait(uint64_t timeoutNs) {
    if (!m_sync) return true;
    GLenum r = glClientWaitSync(m_sync, GL_SYNC_FLUSH_COMMANDS_BIT, timeoutNs);
    return r == GL_ALREADY_SIGNALED || r == GL_CONDITION_SATISFIED;
}

GpuTimer::GpuTimer() : m_query(createQuery(GL_TIME_ELAPSED, "gpu-timer")) {}
void GpuTimer::begin() { glBeginQuery(GL_TIME_ELAPSED, m_query.id()); }
void GpuTimer::end() { glEndQuery(GL_TIME_ELAPSED); }
double GpuTimer::elapsedMs() {
    GLuint64 ns = 0;
    glGetQueryObjectui64v(m_query.id(), GL_QUERY_RESULT, &ns);
    return double(ns) * 1e-6;
}

void barrierAfterComputeWrites() {
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                    GL_TEXTURE_FETCH_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

}  // namespace volstyle::core::gl

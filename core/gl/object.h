#pragma once
/// \file object.h
/// Move-only RAII owners of GL objects (STYLE §3.4). Every glCreate*/glDelete* call of the
/// project lives in object.cpp. All of these must be created, used and destroyed on the thread
/// that owns the GL context.

#include <epoxy/gl.h>

#include <string>
#include <utility>

namespace volstyle::core::gl {

template <typename Traits>
class Object {
public:
    Object() = default;
    explicit Object(GLuint id) : m_id(id) {}
    ~Object() { reset(); }
    Object(const Object&) = delete;
    Object& operator=(const Object&) = delete;
    Object(Object&& o) noexcept : m_id(std::exchange(o.m_id, 0)) {}
    Object& operator=(Object&& o) noexcept {
        if (this != &o) {
            reset();
            m_id = std::exchange(o.m_id, 0);
        }
        return *this;
    }

    GLuint id() const { return m_id; }
    explicit operator bool() const { return m_id != 0; }
    void reset() {
        if (m_id) Traits::destroy(m_id);
        m_id = 0;
    }

private:
    GLuint m_id = 0;
};

struct BufferTraits { static void destroy(GLuint id); };
struct TextureTraits { static void destroy(GLuint id); };
struct ProgramTraits { static void destroy(GLuint id); };
struct SamplerTraits { static void destroy(GLuint id); };
struct QueryTraits { static void destroy(GLuint id); };
struct FramebufferTraits { static void destroy(GLuint id); };
struct VertexArrayTraits { static void destroy(GLuint id); };

using Buffer = Object<BufferTraits>;
using Texture = Object<TextureTraits>;
using Program = Object<ProgramTraits>;
using Sampler = Object<SamplerTraits>;
using Query = Object<QueryTraits>;
using Framebuffer = Object<FramebufferTraits>;
using VertexArray = Object<VertexArrayTraits>;

/// Creation, each with a debug label (glObjectLabel) that shows in KHR_debug messages.
Buffer createBuffer(size_t bytes, const void* data, GLbitfield storageFlags, const std::string& label);
Texture createTexture(GLenum target, const std::string& label);
/// Writes `bytes` of `data` into `buffer` at `offset` through staging buffers created with the data
/// (at most kWriteChunkBytes each) and GPU copies — a driver workaround: on NVIDIA's driver (580,
/// H200) a glNamedBufferSubData into a buffer of more than 64 KiB after a glClearNamedBufferData
/// of it was lost, the buffer read back zeros (seen on the device machine; the solver's joint
/// emission + albedo vectors were the first to cross 64 KiB). As with glNamedBufferSubData, shader
/// writes to `buffer` need a barrier first. glNamedBufferSubData stays only where a small block is
/// written whole (GpuDevice::setParams, the translucent slices' 96-byte polygons).
void writeBuffer(const Buffer& buffer, size_t offset, size_t bytes, const void* data);
constexpr size_t kWriteChunkBytes = size_t(32) << 20;  ///< so an upload never doubles its size on the GPU
Program createProgram(const std::string& label);
Sampler createSampler(const std::string& label);
Query createQuery(GLenum target, const std::string& label);
Framebuffer createFramebuffer(const std::string& label);
VertexArray createVertexArray(const std::string& label);
/// A w×h 2D texture of `format` (one level), sampled with `filter` (GL_NEAREST or GL_LINEAR) and
/// clamped to its edge.
Texture createTexture2D(GLenum format, int w, int h, GLenum filter, const std::string& label);
/// Throws GpuError naming `what` unless `fb` is complete.
void checkFramebufferComplete(const Framebuffer& fb, const std::string& what);

/// A fence sync object (not a GLuint name, so it has its own owner).
class Fence {
public:
    Fence() = default;
    ~Fence();
    Fence(Fence&& o) noexcept : m_sync(std::exchange(o.m_sync, nullptr)) {}
    Fence& operator=(Fence&& o) noexcept;
    Fence(const Fence&) = delete;
    Fence& operator=(const Fence&) = delete;
    /// Inserts a fence after the commands issued so far.
    static Fence insert();
    /// Waits up to `timeoutNs` for the GPU to pass the fence; true when it has.
    bool wait(uint64_t timeoutNs = ~uint64_t(0));

private:
    GLsync m_sync = nullptr;
};

/// Measures GPU time of the commands between begin() and end() (GL_TIME_ELAPSED).
class GpuTimer {
public:
    GpuTimer();
    void begin();
    void end();
    /// Milliseconds; blocks until the result is available.
    double elapsedMs();

    /// begin() now, end() when the scope is left, by a throw too: a query left open would make
    /// the next begin() on this thread fail.
    class Scope {
    public:
        explicit Scope(GpuTimer& timer) : m_timer(timer) { m_timer.begin(); }
        ~Scope() { m_timer.end(); }
        Scope(const Scope&) = delete;
        Scope& operator=(const Scope&) = delete;

    private:
        GpuTimer& m_timer;
    };

private:
    Query m_query;
};

/// Makes writes by compute shaders visible to later reads (names for intent, STYLE §3.4).
void barrierAfterComputeWrites();

}  // namespace volstyle::core::gl

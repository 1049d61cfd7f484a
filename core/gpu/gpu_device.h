#pragma once
/// \file gpu_device.h
/// The one GPU object every engine takes (renderer, projector, vector operations, and the
/// engines to come): the GL context, the compiled programs, the parameter uniform buffer and the
/// cache of derived resources. Engines share these through the device and never reach into each
/// other. The server and the CLI create GL only through GpuDevice::create. GL thread only.
///
/// This header is GL-free (no epoxy): the server and CLI include it; kernels' C++ sides use
/// program() and setParams(), whose GL types they include themselves.

#include <memory>
#include <typeindex>

#include "core/gl/context.h"
#include "core/gpu/resource_cache.h"

namespace volstyle::core {

namespace gl {
class ShaderBuilder;
template <typename Traits>
class Object;
struct ProgramTraits;
using Program = Object<ProgramTraits>;
}  // namespace gl

class GpuDevice {
public:
    /// Creates the GL context (throws GpuError with the reason) and the device on this thread.
    static std::unique_ptr<GpuDevice> create(const gl::ContextOptions& options = {});
    /// A device on a context the caller keeps alive (tests share one context).
    explicit GpuDevice(gl::Context& context);
    ~GpuDevice();
    GpuDevice(const GpuDevice&) = delete;
    GpuDevice& operator=(const GpuDevice&) = delete;

    const gl::Capabilities& capabilities() const { return m_context.capabilities(); }
    bool isOwnedByThisThread() const { return m_context.isOwnedByThisThread(); }
    void finish() { m_context.finish(); }

    /// The compiled program of a shader variant: compiled once, then cached by its variant key.
    const gl::Program& program(const gl::ShaderBuilder& builder);
    /// Uploads a parameter block (layout.h) and binds it at uniform binding `binding`
    /// (kBindingParams, 0, unless the block has a binding of its own) for the next dispatches.
    /// Each block type has a buffer of its own, so the vector kernels' updates never rewrite the
    /// buffer a march kernel still reads (drivers would stall or copy).
    template <typename Block>
    void setParams(const Block& block, int binding = 0) {
        setParams(std::type_index(typeid(Block)), &block, sizeof(Block), binding);
    }
    /// Derived resources shared by every engine (light-depth volumes, environment textures).
    ResourceCache& cache() { return m_cache; }

private:
    struct Programs;
    void setParams(std::type_index block, const void* data, size_t bytes, int binding);
    GpuDevice(std::unique_ptr<gl::Context> owned, gl::Context& context);

    std::unique_ptr<gl::Context> m_owned;
    gl::Context& m_context;
    std::unique_ptr<Programs> m_programs;
    ResourceCache m_cache;
};

}  // namespace volstyle::core

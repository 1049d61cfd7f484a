#include "core/gpu/gpu_device.h"

#include <algorithm>

#include "core/shaders/layout.h"

namespace volstyle::core {

/// Derived resources kept at once: two frames' worth of light-depth volumes, plus an environment.
/// Resources in use stay alive beyond it (shared ownership), so this bounds memory, not safety.
constexpr size_t kCachedResources = 2 * layout::kLightSlots + 1;

void ResourceCache::evict() {
    while (m_entries.size() > m_capacity) {
        auto oldest = std::min_element(m_entries.begin(), m_entries.end(),
                                       [](const auto& a, const auto& b) { return a.second.lastUsed < b.second.lastUsed; });
        m_entries.erase(oldest);
    }
}

std::unique_ptr<GpuDevice> GpuDevice::create(const gl::ContextOptions& options) {
    std::unique_ptr<gl::Context> context = gl::Context::create(options);
    gl::Context& ref = *context;
    return std::unique_ptr<GpuDevice>(new GpuDevice(std::move(context), ref));
}

GpuDevice::GpuDevice(gl::Context& context) : GpuDevice(nullptr, context) {}

GpuDevice::GpuDevice(std::unique_ptr<gl::Context> owned, gl::Context& context)
    : m_owned(std::move(owned)), m_context(context), m_cache(kCachedResources) {}

GpuDevice::~GpuDevice() {
    // GL objects go before the context that owns them.
    m_cache.clear();
    m_programs.clear();
    m_params.reset();
}

const gl::Program& GpuDevice::program(const gl::ShaderBuilder& builder) {
    std::string key = builder.variantKey();
    auto it = m_programs.find(key);
    if (it == m_programs.end()) it = m_programs.emplace(key, builder.buildCompute()).first;
    return it->second;
}

void GpuDevice::setParams(const void* data, size_t bytes) {
    if (bytes > m_paramsCapacity) {
        m_params = gl::createBuffer(bytes, nullptr, GL_DYNAMIC_STORAGE_BIT, "params");
        m_paramsCapacity = bytes;
    }
    glNamedBufferSubData(m_params.id(), 0, GLsizeiptr(bytes), data);
    glBindBufferBase(GL_UNIFORM_BUFFER, layout::kBindingParams, m_params.id());
}

}  // namespace volstyle::core

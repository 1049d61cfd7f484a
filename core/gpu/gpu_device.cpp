#include "core/gpu/gpu_device.h"

#include <algorithm>
#include <map>
#include <string>

#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
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

/// The GL objects the device owns.
struct GpuDevice::Programs {
    std::map<std::string, gl::Program> byVariant;
    std::map<std::type_index, gl::Buffer> paramsByBlock;
};

std::unique_ptr<GpuDevice> GpuDevice::create(const gl::ContextOptions& options) {
    std::unique_ptr<gl::Context> context = gl::Context::create(options);
    gl::Context& ref = *context;
    return std::unique_ptr<GpuDevice>(new GpuDevice(std::move(context), ref));
}

GpuDevice::GpuDevice(gl::Context& context) : GpuDevice(nullptr, context) {}

GpuDevice::GpuDevice(std::unique_ptr<gl::Context> owned, gl::Context& context)
    : m_owned(std::move(owned)), m_context(context), m_programs(std::make_unique<Programs>()), m_cache(kCachedResources) {}

GpuDevice::~GpuDevice() {
    // GL objects go before the context that owns them.
    m_cache.clear();
    m_programs.reset();
}

const gl::Program& GpuDevice::program(const gl::ShaderBuilder& builder) {
    std::string key = builder.variantKey();
    auto& programs = m_programs->byVariant;
    auto it = programs.find(key);
    if (it == programs.end()) it = programs.emplace(key, builder.build()).first;
    return it->second;
}

void GpuDevice::setParams(std::type_index block, const void* data, size_t bytes, int binding) {
    gl::Buffer& buffer = m_programs->paramsByBlock[block];
    if (!buffer) buffer = gl::createBuffer(bytes, nullptr, GL_DYNAMIC_STORAGE_BIT, "params");
    glNamedBufferSubData(buffer.id(), 0, GLsizeiptr(bytes), data);
    glBindBufferBase(GL_UNIFORM_BUFFER, GLuint(binding), buffer.id());
}

}  // namespace volstyle::core

#include "core/gl/gpu_memory.h"

#include <epoxy/gl.h>

namespace volstyle::core::gl {

namespace {
constexpr const char* kNvx = "GL_NVX_gpu_memory_info";
constexpr const char* kAti = "GL_ATI_meminfo";
}  // namespace

std::string gpuMemorySource() {
    if (epoxy_has_gl_extension(kNvx)) return kNvx;
    if (epoxy_has_gl_extension(kAti)) return kAti;
    return "";
}

GpuMemory queryGpuMemory(const std::string& source) {
    GpuMemory m;
    if (source == kNvx) {
        GLint total = 0, available = 0;
        glGetIntegerv(GL_GPU_MEMORY_INFO_TOTAL_AVAILABLE_MEMORY_NVX, &total);  // KiB
        glGetIntegerv(GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX, &available);
        m.totalBytes = 1024LL * total;
        m.availableBytes = 1024LL * available;
    } else if (source == kAti) {
        GLint free[4] = {0, 0, 0, 0};  // KiB: free in the pool, largest block, free auxiliary, largest auxiliary
        glGetIntegerv(GL_TEXTURE_FREE_MEMORY_ATI, free);
        m.availableBytes = 1024LL * free[0];
    }
    return m;
}

}  // namespace volstyle::core::gl

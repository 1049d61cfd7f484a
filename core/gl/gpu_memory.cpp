#include "core/gl/gpu_memory.h"

#include <epoxy/gl.h>

namespace volstyle::core::gl {

namespace {
// GL_NVX_gpu_memory_info and GL_ATI_meminfo's enums (libepoxy's headers name them too, but not
// every version: kept here with the extensions' own values). Both report KiB.
constexpr GLenum kNvxTotalAvailableKiB = 0x9048;    // GPU_MEMORY_INFO_TOTAL_AVAILABLE_MEMORY_NVX
constexpr GLenum kNvxCurrentAvailableKiB = 0x9049;  // GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX
constexpr GLenum kAtiTextureFreeKiB = 0x87FC;       // TEXTURE_FREE_MEMORY_ATI: 4 values, [0] free in the pool
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
        glGetIntegerv(kNvxTotalAvailableKiB, &total);
        glGetIntegerv(kNvxCurrentAvailableKiB, &available);
        m.totalBytes = 1024LL * total;
        m.availableBytes = 1024LL * available;
    } else if (source == kAti) {
        GLint free[4] = {0, 0, 0, 0};
        glGetIntegerv(kAtiTextureFreeKiB, free);
        m.availableBytes = 1024LL * free[0];
    }
    return m;
}

}  // namespace volstyle::core::gl

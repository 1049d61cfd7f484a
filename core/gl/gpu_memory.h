#pragma once
/// \file gpu_memory.h
/// The GPU memory a driver reports (issue #41: `/metrics`), where it reports it: NVIDIA's
/// GL_NVX_gpu_memory_info (total and available) or AMD's GL_ATI_meminfo (available texture
/// memory). Mesa's llvmpipe reports neither; the server then says so instead of guessing.

#include <string>

namespace volstyle::core::gl {

/// Which extension the context can read its memory through, checked once at start-up: the name
/// of GL_NVX_gpu_memory_info or GL_ATI_meminfo, or "" when neither is present.
std::string gpuMemorySource();

struct GpuMemory {
    long long totalBytes = -1;      ///< the GPU's dedicated memory; -1 when not reported
    long long availableBytes = -1;  ///< what is free now; -1 when not reported
};

/// Reads the figures through `source` (from gpuMemorySource()) on the context's thread.
GpuMemory queryGpuMemory(const std::string& source);

}  // namespace volstyle::core::gl

#pragma once
// One GL context for the whole test binary, created on first use on the main thread. Without an
// EGL context (no Mesa, no GPU) GL tests skip with the reason instead of failing.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "core/gl/context.h"
#include "core/gpu/gpu_device.h"
#include "core/render/renderer.h"

namespace volstyle::test {

/// The shared context, or nullptr with `reason` set.
core::gl::Context* glContext(std::string* reason = nullptr);
/// The device on the shared context (kept for the whole run so programs compile once).
core::GpuDevice& device();
/// A renderer on the shared device.
core::Renderer& sharedRenderer();

/// Largest |a − b| / (|b| + floor) over RGB of all pixels.
double maxRelativeError(const core::Image& a, const core::Image& b, double floor);

/// Whether a missing GL context fails tests instead of skipping them: VOLSTYLE_GL_REQUIRED=1
/// (.ci/run sets it, so CI never passes with its GL and HTTP tests skipped; issue #34).
inline bool glRequired() {
    const char* v = std::getenv("VOLSTYLE_GL_REQUIRED");
    return v && std::string(v) != "" && std::string(v) != "0";
}

}  // namespace volstyle::test

#define VOLSTYLE_REQUIRE_GL()                                                                         \
    do {                                                                                              \
        std::string volstyle_reason_;                                                                 \
        if (!::volstyle::test::glContext(&volstyle_reason_)) {                                        \
            if (::volstyle::test::glRequired())                                                       \
                GTEST_FAIL() << "no EGL/OpenGL 4.5 context (VOLSTYLE_GL_REQUIRED): " << volstyle_reason_; \
            GTEST_SKIP() << "no EGL/OpenGL 4.5 context: " << volstyle_reason_;                        \
        }                                                                                             \
    } while (0)

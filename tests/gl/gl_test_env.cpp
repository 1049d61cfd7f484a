#include "gl_test_env.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "core/base/errors.h"

namespace volstyle::test {

core::gl::Context* glContext(std::string* reason) {
    static std::string failure;
    static std::unique_ptr<core::gl::Context> context = [] {
        try {
            return core::gl::Context::create();
        } catch (const Error& e) {
            failure = e.what();
            return std::unique_ptr<core::gl::Context>();
        }
    }();
    if (reason) *reason = failure;
    return context.get();
}

core::GpuDevice& device() {
    static core::GpuDevice device(*glContext());
    return device;
}

core::Renderer& sharedRenderer() {
    static core::Renderer renderer(device());
    return renderer;
}

double maxRelativeError(const core::Image& a, const core::Image& b, double floor) {
    double worst = 0;
    for (size_t i = 0; i < a.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            double x = a.rgba[4 * i + c], y = b.rgba[4 * i + c];
            worst = std::max(worst, std::abs(x - y) / (std::abs(y) + floor));
        }
    return worst;
}

}  // namespace volstyle::test

#include "core/stylize/morphology.h"

#include <algorithm>
#include <cmath>

#include "core/base/errors.h"
#include "core/gl/shader_builder.h"
#include "core/shaders/layout.h"
#include "core/stylize/morphology_gpu.h"

namespace volstyle::core {

int discHalfWidth(int radius, int dy) {
    int w = int(std::floor(std::sqrt(std::max(0.0, double(radius) * radius - double(dy) * dy))));
    while (w * w + dy * dy > radius * radius) --w;  // exact in integers whatever sqrt rounds to
    while ((w + 1) * (w + 1) + dy * dy <= radius * radius) ++w;
    return w;
}

namespace {

/// The extremum over the element at every texel (`takeMin`: dilation of occluders).
std::vector<float> bruteForce(const std::vector<float>& in, int n, int r, MorphShape shape, bool takeMin) {
    std::vector<float> out(in.size());
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            float best = takeMin ? 3.0e38f : -3.0e38f;
            for (int dy = -r; dy <= r; ++dy) {
                const int w = shape == MorphShape::Box ? r : discHalfWidth(r, dy);
                for (int dx = -w; dx <= w; ++dx) {
                    const bool inside = x + dx >= 0 && x + dx < n && y + dy >= 0 && y + dy < n;
                    const float v = inside ? in[size_t(y + dy) * n + size_t(x + dx)] : 1.0f;  // outside: empty
                    best = takeMin ? std::min(best, v) : std::max(best, v);
                }
            }
            out[size_t(y) * n + x] = best;
        }
    return out;
}

struct MorphPass {
    GpuDevice& device;
    int n;
    gl::Buffer scratch;

    MorphPass(GpuDevice& d, int side, int maxHalfWidth)
        : device(d), n(side),
          scratch(gl::createBuffer(sizeof(float) * 2 * size_t(side) * size_t(side + 2 * maxHalfWidth), nullptr, 0,
                                   "morphology-scratch")) {}

    void run(const gl::Buffer& in, const gl::Buffer& out, int halfWidth, bool columns, int dy, bool takeMin, bool fold) {
        layout::MorphParams p;
        p.size = {n, halfWidth, columns ? 1 : 0, dy};
        p.op = {takeMin ? 0 : 1, fold ? 1 : 0, 0, 0};
        device.setParams(p);
        glUseProgram(device.program(gl::ShaderBuilder("shadow_morphology.comp")).id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMorphIn, in.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMorphOut, out.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMorphScratch, scratch.id());
        glDispatchCompute(GLuint((n + layout::kWorkgroup1D - 1) / layout::kWorkgroup1D), 1, 1);
        gl::barrierAfterComputeWrites();
    }

    /// One dilation (takeMin) or erosion of `in` into `out` with the element.
    void apply(const gl::Buffer& in, const gl::Buffer& out, const gl::Buffer& tmp, int r, MorphShape shape, bool takeMin) {
        if (shape == MorphShape::Box) {
            run(in, tmp, r, false, 0, takeMin, false);  // rows
            run(tmp, out, r, true, 0, takeMin, false);  // then columns: a box is separable
        } else {
            for (int dy = -r; dy <= r; ++dy) run(in, out, discHalfWidth(r, dy), false, dy, takeMin, dy > -r);
        }
    }
};

}  // namespace

void closeDepthBuffer(GpuDevice& device, gl::Buffer& depth, int n, int radius, MorphShape shape) {
    if (radius < 0 || radius > 256) throw InvalidArgument("closing radius must be in [0, 256] texels");
    if (radius == 0) return;
    const size_t bytes = sizeof(float) * size_t(n) * n;
    gl::Buffer a = gl::createBuffer(bytes, nullptr, 0, "morphology-a"), b = gl::createBuffer(bytes, nullptr, 0, "morphology-b");
    MorphPass pass(device, n, radius);
    pass.apply(depth, a, b, radius, shape, true);   // dilation: occluders grow into the holes
    pass.apply(a, depth, b, radius, shape, false);  // erosion: and shrink back outside them
}

void erodeBoxBuffer(GpuDevice& device, gl::Buffer& depth, int n, int radius) {
    if (radius <= 0) return;
    const size_t bytes = sizeof(float) * size_t(n) * n;
    gl::Buffer tmp = gl::createBuffer(bytes, nullptr, 0, "morphology-tmp");
    MorphPass pass(device, n, radius);
    pass.run(depth, tmp, radius, false, 0, false, false);  // rows, then columns: a box is separable
    pass.run(tmp, depth, radius, true, 0, false, false);
}

void foldMinimum(GpuDevice& device, const gl::Buffer& from, const gl::Buffer& into, int n) {
    MorphPass pass(device, n, 0);
    pass.run(from, into, 0, false, 0, true, true);  // a one-texel window is the value itself
}

std::vector<float> closingReference(const std::vector<float>& depth, int n, int radius, MorphShape shape) {
    if (radius == 0) return depth;
    return bruteForce(bruteForce(depth, n, radius, shape, true), n, radius, shape, false);
}

std::vector<float> closingOnGpu(GpuDevice& device, const std::vector<float>& depth, int n, int radius, MorphShape shape) {
    VOLSTYLE_CHECK(depth.size(), ==, size_t(n) * n);
    gl::Buffer buffer = gl::createBuffer(depth.size() * sizeof(float), depth.data(), GL_DYNAMIC_STORAGE_BIT, "morphology-depth");
    closeDepthBuffer(device, buffer, n, radius, shape);
    std::vector<float> out(depth.size());
    glGetNamedBufferSubData(buffer.id(), 0, GLsizeiptr(out.size() * sizeof(float)), out.data());
    return out;
}

}  // namespace volstyle::core

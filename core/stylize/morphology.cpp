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

Octagon octagonOf(int radius) {
    const int b = int(std::lround(radius * (1 - 1 / std::sqrt(2.0))));
    return {radius - 2 * b, b};
}

int elementHalfWidth(int radius, int dy, MorphShape shape) {
    if (std::abs(dy) > radius) return -1;
    if (shape == MorphShape::Box) return radius;
    if (radius <= kExactDiscRadius) return discHalfWidth(radius, dy);
    // The octagon: (dx, dy) = s + t (1, 1) + u (1, −1) with |s|∞ ≤ a and |t|, |u| ≤ b.
    const Octagon o = octagonOf(radius);
    for (int dx = radius; dx >= 0; --dx)
        for (int t = -o.b; t <= o.b; ++t)
            for (int u = -o.b; u <= o.b; ++u)
                if (std::abs(dx - t - u) <= o.a && std::abs(dy - t + u) <= o.a) return dx;
    return -1;
}

namespace {

/// The extremum over the element at every texel (`takeMin`: dilation of occluders).
std::vector<float> bruteForce(const std::vector<float>& in, int n, int r, MorphShape shape, bool takeMin) {
    std::vector<float> out(in.size());
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            float best = takeMin ? 3.0e38f : -3.0e38f;
            for (int dy = -r; dy <= r; ++dy) {
                const int w = elementHalfWidth(r, dy, shape);
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

    enum Lines { Rows = 0, Columns = 1, Diagonals = 2, AntiDiagonals = 3 };

    void run(const gl::Buffer& in, const gl::Buffer& out, int halfWidth, Lines lines, int dy, bool takeMin, bool fold) {
        glUseProgram(device.program(gl::ShaderBuilder("shadow_morphology.comp")).id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMorphIn, in.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMorphOut, out.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMorphScratch, scratch.id());
        // 2n − 1 diagonals, in parts of n lines (the scratch holds n).
        const int count = lines >= Diagonals ? 2 * n - 1 : n;
        for (int first = 0; first < count; first += n) {
            layout::MorphParams p;
            p.size = {n, halfWidth, int(lines), dy};
            p.op = {takeMin ? 0 : 1, fold ? 1 : 0, first, 0};
            device.setParams(p);
            glDispatchCompute(GLuint((std::min(n, count - first) + layout::kWorkgroup1D - 1) / layout::kWorkgroup1D), 1, 1);
            gl::barrierAfterComputeWrites();
        }
    }

    /// One dilation (takeMin) or erosion of `in` into `out` with the element.
    void apply(const gl::Buffer& in, const gl::Buffer& out, const gl::Buffer& tmp, int r, MorphShape shape, bool takeMin) {
        if (shape == MorphShape::Box) {
            run(in, tmp, r, Rows, 0, takeMin, false);
            run(tmp, out, r, Columns, 0, takeMin, false);  // a box is separable
        } else if (r <= kExactDiscRadius) {
            for (int dy = -r; dy <= r; ++dy) run(in, out, discHalfWidth(r, dy), Rows, dy, takeMin, dy > -r);
        } else {
            // The octagon is the Minkowski sum of four segments: an operation by it is four 1D
            // passes, each O(1) per texel whatever their length.
            const Octagon o = octagonOf(r);
            run(in, tmp, o.a, Rows, 0, takeMin, false);
            run(tmp, out, o.a, Columns, 0, takeMin, false);
            run(out, tmp, o.b, Diagonals, 0, takeMin, false);
            run(tmp, out, o.b, AntiDiagonals, 0, takeMin, false);
        }
    }
};

}  // namespace

void closeDepthBuffer(GpuDevice& device, gl::Buffer& depth, int n, int radius, MorphShape shape) {
    if (radius < 0 || radius > kMaxClosingRadiusPx)  // the scene's range (Manipulation::check)
        throw InvalidArgument("closing radius must be in [0, " + std::to_string(kMaxClosingRadiusPx) + "] texels");
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
    pass.run(depth, tmp, radius, MorphPass::Rows, 0, false, false);  // rows, then columns: a box is separable
    pass.run(tmp, depth, radius, MorphPass::Columns, 0, false, false);
}

void foldMinimum(GpuDevice& device, const gl::Buffer& from, const gl::Buffer& into, int n) {
    MorphPass pass(device, n, 0);
    pass.run(from, into, 0, MorphPass::Rows, 0, true, true);  // a one-texel window is the value itself
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

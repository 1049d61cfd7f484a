// The GPU side of shadow_edits.h: Eq. 3 (shadow_dilate.comp) and Eq. 4 (shadow_holes.comp).
#include <functional>

#include "core/base/errors.h"
#include "core/gl/shader_builder.h"
#include "core/shaders/layout.h"
#include "core/stylize/morphology_gpu.h"

namespace volstyle::core {

namespace {

void dispatchOver(int n) {
    const int g = layout::kWorkgroup2D;
    glDispatchCompute(GLuint((n + g - 1) / g), GLuint((n + g - 1) / g), 1);
    gl::barrierAfterComputeWrites();
}

std::vector<float> roundTrip(const std::vector<float>& depth, int n, const std::function<void(gl::Buffer&)>& pass) {
    VOLSTYLE_CHECK(depth.size(), ==, size_t(n) * n);
    gl::Buffer buffer = gl::createBuffer(depth.size() * sizeof(float), depth.data(), GL_DYNAMIC_STORAGE_BIT, "shadow-edit-test");
    pass(buffer);
    std::vector<float> out(depth.size());
    glGetNamedBufferSubData(buffer.id(), 0, GLsizeiptr(out.size() * sizeof(float)), out.data());
    return out;
}

}  // namespace

void dilateEpipolarBuffer(GpuDevice& device, gl::Buffer& depth, int n, const Epipole& e, int kernelTexels) {
    if (kernelTexels <= 0) return;
    gl::Buffer source = gl::createBuffer(sizeof(float) * size_t(n) * n, nullptr, 0, "dilation-source");
    glCopyNamedBufferSubData(depth.id(), source.id(), 0, 0, GLsizeiptr(sizeof(float) * size_t(n) * n));
    layout::EditParams p;
    p.size = {n, kernelTexels, 0, 0};
    p.epipole = {float(e.x), float(e.y), float(e.depth), float(e.sense)};
    device.setParams(p);
    glUseProgram(device.program(gl::ShaderBuilder("shadow_dilate.comp")).id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingEditIn, source.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingEditOut, depth.id());
    dispatchOver(n);
}

void cutHolesBuffer(GpuDevice& device, gl::Buffer& depth, int n, const HoleMap& h) {
    layout::EditParams p;
    p.size = {n, 0, h.octaves, int32_t(h.seed)};
    p.holeFrame = {float(h.originX), float(h.originY), float(h.stepX), float(h.stepY)};
    p.holeNoise = {h.threshold, float(h.persistence), float(h.offsetX), float(h.offsetY)};
    device.setParams(p);
    glUseProgram(device.program(gl::ShaderBuilder("shadow_holes.comp")).id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingEditOut, depth.id());
    dispatchOver(n);
}

std::vector<float> epipolarDilationOnGpu(GpuDevice& device, const std::vector<float>& depth, int n, const Epipole& e, int kernelTexels) {
    return roundTrip(depth, n, [&](gl::Buffer& b) { dilateEpipolarBuffer(device, b, n, e, kernelTexels); });
}

std::vector<float> holesOnGpu(GpuDevice& device, const std::vector<float>& depth, int n, const HoleMap& h) {
    return roundTrip(depth, n, [&](gl::Buffer& b) { cutHolesBuffer(device, b, n, h); });
}

}  // namespace volstyle::core

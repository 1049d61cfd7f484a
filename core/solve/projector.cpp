#include "core/solve/projector.h"

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

/// Rays stop once every channel's transmittance is below this: forward and adjoint use the same
/// cut-off, so they stay exact transposes; what it drops is below 1e-8 of a pixel.
constexpr float kProjectorTermination = 1e-8f;

Projector::Projector(GpuDevice& device, GpuVolume& volume, const Lighting& lighting, Unknown unknown,
                     BasisType basis, Int3 unknownDims, double stepVoxels, bool exactTraversal)
    : m_device(device), m_volume(volume), m_lighting(lighting), m_unknown(unknown), m_basis(basis),
      m_unknownDims(unknownDims), m_step(stepVoxels), m_exactTraversal(exactTraversal) {
    if (unknownDims.x < 1 || unknownDims.y < 1 || unknownDims.z < 1)
        throw InvalidArgument("Projector: the unknown grid must have at least one voxel");
    if (unknown == Unknown::Extinction) m_lighting.lights.clear();  // log-space tomography: no light
    m_useFloatAtomics = device.capabilities().hasFloatAtomics;
}

void Projector::setUseFloatAtomics(bool use) {
    if (use && !m_device.capabilities().hasFloatAtomics)
        throw InvalidArgument("Projector: this GL context has no GL_NV_shader_atomic_float");
    m_useFloatAtomics = use;
}

void Projector::addView(const Camera& camera) {
    camera.validate();
    RenderSettings settings;
    settings.stepVoxels = m_step;
    settings.exactTraversal = m_exactTraversal;
    RenderStats stats;
    View view{camera, prepareMarch(m_device, m_volume, camera, m_lighting, settings, stats), m_pixelCount};
    const Int3 n = m_volume.dims();
    layout::MarchParams& p = view.setup.params;
    p.unknownDims = {m_unknownDims.x, m_unknownDims.y, m_unknownDims.z, 0};
    p.unknownScale = {float(m_unknownDims.x) / float(n.x), float(m_unknownDims.y) / float(n.y),
                      float(m_unknownDims.z) / float(n.z), 0};
    p.unknownLayout = {int(m_unknownDims.volume()), 0, 0, 0};
    p.viewPixels = {int(m_pixelCount), 0, 0, 0};
    p.projectorCutoff = {kProjectorTermination, 0, 0, 0};
    m_pixelCount += size_t(camera.width) * camera.height;
    m_views.push_back(std::move(view));
}

void Projector::dispatch(bool adjoint, const GpuVector& unknowns, const GpuVector& pixels) {
    VOLSTYLE_CHECK(unknowns.size(), ==, elementCount());
    VOLSTYLE_CHECK(pixels.size(), ==, m_pixelCount);
    const bool needsLight = m_unknown == Unknown::Albedo || m_unknown == Unknown::EmissionAlbedo;
    for (const View& v : m_views) {
        gl::ShaderBuilder builder("project.comp");
        builder.define("VOLSTYLE_ADJOINT", adjoint ? 1 : 0)
            .define("VOLSTYLE_UNKNOWN", int(m_unknown))
            .define("VOLSTYLE_BASIS", int(m_basis))
            .define("VOLSTYLE_NUM_LIGHTS", needsLight ? (long long)v.setup.lightDepth.size() : 0)
            .define("VOLSTYLE_SKIP_EMPTY", 1)
            .define("VOLSTYLE_EXACT_TRAVERSAL", m_exactTraversal ? 1 : 0);
        if (adjoint && m_useFloatAtomics) {
            builder.define("VOLSTYLE_HAS_FLOAT_ATOMICS", 1).extension("GL_NV_shader_atomic_float");
        }
        glUseProgram(m_device.program(builder).id());
        bindMarch(m_device, m_volume, v.setup);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingUnknown, unknowns.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, adjoint ? layout::kBindingResidual : layout::kBindingImageOut,
                         pixels.id());
        const int g = layout::kWorkgroup2D;
        glDispatchCompute(GLuint((v.camera.width + g - 1) / g), GLuint((v.camera.height + g - 1) / g), 1);
    }
    gl::barrierAfterComputeWrites();
}

void Projector::forward(const GpuVector& a, GpuVector& pixels) {
    const auto t0 = Clock::now();
    dispatch(false, a, pixels);
    m_device.finish();
    m_stats.forwardMs += msSince(t0);
    m_stats.forwardCalls++;
}

void Projector::adjoint(const GpuVector& pixels, GpuVector& a) {
    const auto t0 = Clock::now();
    a.fill(0.0f);
    dispatch(true, a, pixels);
    m_device.finish();
    m_stats.adjointMs += msSince(t0);
    m_stats.adjointCalls++;
}

}  // namespace volstyle::core

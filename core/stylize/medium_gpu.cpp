#include "core/stylize/medium_gpu.h"

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/gl/shader_builder.h"

namespace volstyle::core {
namespace {

gl::Texture texture3D(Int3 n, const float* data, const char* label) {
    gl::Texture t = gl::createTexture(GL_TEXTURE_3D, label);
    glTextureStorage3D(t.id(), 1, GL_R32F, n.x, n.y, n.z);
    if (data) {
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glTextureSubImage3D(t.id(), 0, 0, 0, 0, n.x, n.y, n.z, GL_RED, GL_FLOAT, data);
    }
    // Trilinear between voxel centres, clamped to the edge voxels inside the box (as core::Volume).
    glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R}) glTextureParameteri(t.id(), wrap, GL_CLAMP_TO_EDGE);
    return t;
}

}  // namespace

double StylizerMediumCache::bind(GpuDevice& device, const std::optional<StylizerVolume>& volume, layout::StylizeParams& p) {
    p.volumeLo = {0, 0, 0, 0};
    p.volumeHi = {1, 1, 1, 0};
    if (!volume) {
        if (!m_empty) {
            const float one = 1;
            m_empty = texture3D({1, 1, 1}, &one, "stylizer-no-medium");
        }
        glBindTextureUnit(layout::kUnitStylizeDensity, m_empty.id());
        glBindTextureUnit(layout::kUnitStylizeTransmittance, m_empty.id());
        return 0;
    }
    const auto t0 = Clock::now();
    const StylizerVolume& v = *volume;
    const Int3 n = v.grid->dims;
    p.volumeLo = {float(v.lo.x), float(v.lo.y), float(v.lo.z), float(v.steps)};
    p.volumeHi = {float(v.hi.x), float(v.hi.y), float(v.hi.z), v.lightTransmittance ? 1.0f : 0.0f};
    bool built = false;
    const DensityKey densityKey{v.grid->id, v.extinctionScale};
    if (m_densityKey != densityKey) {
        std::vector<float> sigma(v.grid->sigma);
        for (float& s : sigma) s = float(s * v.extinctionScale);
        m_density = texture3D(n, sigma.data(), "stylizer-density");
        m_densityKey = densityKey;
        m_lightKey.reset();
        built = true;
    }
    glBindTextureUnit(layout::kUnitStylizeDensity, m_density.id());
    const LightKey lightKey{double(v.grid->id), v.extinctionScale, v.lo.x, v.lo.y, v.lo.z, v.hi.x, v.hi.y, v.hi.z, double(p.options.z),
                            p.lightDirection.x, p.lightDirection.y, p.lightDirection.z, p.spot.x, p.spot.y, p.spot.z};
    if (v.lightTransmittance && m_lightKey != lightKey) {
        m_transmittance = texture3D(n, nullptr, "stylizer-light-optical-depth");
        device.setParams(p);
        glUseProgram(device.program(gl::ShaderBuilder("stylize_transmittance.comp")).id());
        glBindImageTexture(layout::kImageUnitOut, m_transmittance.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
        const int g = layout::kWorkgroup3D;
        glDispatchCompute(GLuint((n.x + g - 1) / g), GLuint((n.y + g - 1) / g), GLuint((n.z + g - 1) / g));
        gl::barrierAfterComputeWrites();
        m_lightKey = lightKey;
        built = true;
    }
    glBindTextureUnit(layout::kUnitStylizeTransmittance, v.lightTransmittance ? m_transmittance.id() : m_density.id());  // off: unread
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory for the stylizer's volume");
    if (!built) return 0;
    device.finish();
    return msSince(t0);
}

}  // namespace volstyle::core

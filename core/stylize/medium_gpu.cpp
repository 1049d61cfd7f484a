#include "core/stylize/medium_gpu.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/gl/shader_builder.h"
#include "core/render/derived_volumes.h"
#include "core/render/render_stats.h"

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

/// A number exactly, for a cache key.
std::string exact(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%a", v);
    return buf;
}

/// A one-channel grid the stylizer derives from the volume on the GPU, in the device's cache.
struct DerivedGrid {
    gl::Texture texture;
};

void dispatchOver(Int3 n) {
    const int g = layout::kWorkgroup3D;
    glDispatchCompute(GLuint((n.x + g - 1) / g), GLuint((n.y + g - 1) / g), GLuint((n.z + g - 1) / g));
    gl::barrierAfterComputeWrites();
}

/// The mean of the volume's RGB extinction per voxel (stylize_extinction_mean.comp), once per
/// extinction version; `built` when it was made.
std::shared_ptr<const DerivedGrid> meanExtinction(GpuDevice& device, const GpuVolume& gpu, bool& built) {
    if (gpu.isSparse()) throw InvalidArgument("the stylizer's heterogeneous medium works on dense volumes only, and this volume is sparse");
    const std::string key = "stylizer-extinction-mean/" + std::to_string(gpu.extinctionVersion());
    if (auto cached = device.cache().find<DerivedGrid>(key)) return cached;
    DerivedGrid made{texture3D(gpu.dims(), nullptr, "stylizer-extinction-mean")};
    glBindTextureUnit(layout::kUnitStylizeDensity, gpu.extinctionTexture());
    glUseProgram(device.program(gl::ShaderBuilder("stylize_extinction_mean.comp")).id());
    glBindImageTexture(layout::kImageUnitOut, made.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatchOver(gpu.dims());
    built = true;
    return device.cache().insert(key, std::make_shared<const DerivedGrid>(std::move(made)));
}

/// The optical depth toward the light per voxel (stylize_transmittance.comp), from the device's
/// cache when the grid, its scale, box and the light are the same; `built` when it was made.
std::shared_ptr<const DerivedGrid> lightOpticalDepth(GpuDevice& device, const StylizerVolume& v, const GpuVolume& gpu,
                                                     layout::StylizeParams& p, bool& built) {
    std::string key = "stylizer-light/" + std::to_string(gpu.extinctionVersion());
    for (double x : {v.extinctionScale, v.lo.x, v.lo.y, v.lo.z, v.hi.x, v.hi.y, v.hi.z, double(p.options.z), double(p.lightDirection.x), double(p.lightDirection.y),
                     double(p.lightDirection.z), double(p.spot.x), double(p.spot.y), double(p.spot.z)})
        key += "/" + exact(x);
    if (auto cached = device.cache().find<DerivedGrid>(key)) return cached;
    const Int3 n = gpu.dims();
    DerivedGrid made{texture3D(n, nullptr, "stylizer-light-optical-depth")};
    device.setParams(p);
    glUseProgram(device.program(gl::ShaderBuilder("stylize_transmittance.comp")).id());
    glBindImageTexture(layout::kImageUnitOut, made.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatchOver(n);
    built = true;
    return device.cache().insert(key, std::make_shared<const DerivedGrid>(std::move(made)));
}

}  // namespace

double bindStylizerMedium(GpuDevice& device, const std::optional<StylizerVolume>& volume, GpuVolume* gpu, layout::StylizeParams& p) {
    p.volumeLo = {0, 0, 0, 0};
    p.volumeHi = {1, 1, 1, 0};
    p.volumeScale = {1, 0, 0, 0};
    ResourceCache& cache = device.cache();
    if (!volume) {
        auto empty = cache.find<gl::Texture>("stylizer-no-medium");
        if (!empty) {
            const float one = 1;
            empty = cache.insert("stylizer-no-medium", std::make_shared<const gl::Texture>(texture3D({1, 1, 1}, &one, "stylizer-no-medium")));
        }
        for (int unit : {layout::kUnitStylizeDensity, layout::kUnitStylizeTransmittance, layout::kUnitStylizeOccupancy})
            glBindTextureUnit(GLuint(unit), empty->id());
        return 0;
    }
    if (!gpu) throw InvalidArgument("/volume: the scene has a volume but none was given to the stylizer (the session has no volume?)");
    const auto t0 = Clock::now();
    const StylizerVolume& v = *volume;
    p.volumeLo = {float(v.lo.x), float(v.lo.y), float(v.lo.z), float(v.steps)};
    p.volumeHi = {float(v.hi.x), float(v.hi.y), float(v.hi.z), v.lightTransmittance ? 1.0f : 0.0f};
    p.volumeScale = {float(v.extinctionScale), 0, 0, 0};
    // The volume's occupancy bricks, as the renderer keeps them (made again only when its
    // extinction changed).
    RenderStats stats;
    updateOccupancy(device, *gpu, stats);
    bool built = stats.occupancyMs > 0;
    glBindTextureUnit(layout::kUnitStylizeDensity, meanExtinction(device, *gpu, built)->texture.id());
    glBindTextureUnit(layout::kUnitStylizeOccupancy, gpu->occupancyTexture());
    std::shared_ptr<const DerivedGrid> depth;
    if (v.lightTransmittance) depth = lightOpticalDepth(device, v, *gpu, p, built);
    glBindTextureUnit(layout::kUnitStylizeTransmittance, depth ? depth->texture.id() : gpu->extinctionTexture());  // off: unread
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory for the stylizer's volume");
    if (!built) return 0;
    device.finish();
    return msSince(t0);
}

}  // namespace volstyle::core

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
    gl::Texture occupancy;  ///< the σt grid's own bricks (a sparse volume's block means); else none: the volume's
};

void dispatchOver(Int3 n) {
    const int g = layout::kWorkgroup3D;
    glDispatchCompute(GLuint((n.x + g - 1) / g), GLuint((n.y + g - 1) / g), GLuint((n.z + g - 1) / g));
    gl::barrierAfterComputeWrites();
}

Int3 ceilDiv(Int3 n, int f) { return {(n.x + f - 1) / f, (n.y + f - 1) / f, (n.z + f - 1) / f}; }

/// The block-mean σt grid of a sparse volume and its bricks (stylize_extinction_mean.comp with
/// VOLSTYLE_SPARSE, stylize_medium_occupancy.comp), blocks of `block`³ voxels.
DerivedGrid blockMeanExtinction(GpuDevice& device, const GpuVolume& gpu, int block) {
    const Int3 d = gpu.dims(), n = ceilDiv(d, block), o = gpu.sparseOffset();
    DerivedGrid made{texture3D(n, nullptr, "stylizer-extinction-mean"), texture3D(ceilDiv(n, layout::kBrickSize), nullptr, "stylizer-medium-occupancy")};
    layout::StylizeMediumParams mp;
    mp.dims = {d.x, d.y, d.z, block};
    mp.sparseOffset = {o.x, o.y, o.z, 0};
    device.setParams(mp);
    glBindTextureUnit(layout::kUnitStylizeDensity, gpu.extinctionTexture());
    glBindTextureUnit(layout::kUnitBrickTable, gpu.brickTableTexture());
    glUseProgram(device.program(gl::ShaderBuilder("stylize_extinction_mean.comp").define("VOLSTYLE_SPARSE", 1)).id());
    glBindImageTexture(layout::kImageUnitOut, made.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatchOver(n);
    glBindTextureUnit(layout::kUnitStylizeDensity, made.texture.id());
    glUseProgram(device.program(gl::ShaderBuilder("stylize_medium_occupancy.comp")).id());
    glBindImageTexture(layout::kImageUnitOut, made.occupancy.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatchOver(ceilDiv(n, layout::kBrickSize));
    return made;
}

/// The mean of the volume's RGB extinction per voxel (stylize_extinction_mean.comp), once per
/// extinction version; `built` when it was made. A sparse volume's is its mean over blocks of
/// `block` voxels a side (stylizerMediumBlock()), with bricks of its own.
std::shared_ptr<const DerivedGrid> meanExtinction(GpuDevice& device, const GpuVolume& gpu, int block, bool& built) {
    const std::string key = "stylizer-extinction-mean/" + std::to_string(gpu.extinctionVersion()) + "/" + std::to_string(block);
    if (auto cached = device.cache().find<DerivedGrid>(key)) return cached;
    built = true;
    if (gpu.isSparse()) return device.cache().insert(key, std::make_shared<const DerivedGrid>(blockMeanExtinction(device, gpu, block)));
    DerivedGrid made{texture3D(gpu.dims(), nullptr, "stylizer-extinction-mean"), {}};
    glBindTextureUnit(layout::kUnitStylizeDensity, gpu.extinctionTexture());
    glUseProgram(device.program(gl::ShaderBuilder("stylize_extinction_mean.comp")).id());
    glBindImageTexture(layout::kImageUnitOut, made.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatchOver(gpu.dims());
    return device.cache().insert(key, std::make_shared<const DerivedGrid>(std::move(made)));
}

/// The optical depth toward the light per voxel (stylize_transmittance.comp), from the device's
/// cache when the grid, its scale, box and the light are the same; `built` when it was made.
std::shared_ptr<const DerivedGrid> lightOpticalDepth(GpuDevice& device, const StylizerVolume& v, const GpuVolume& gpu, Int3 n,
                                                     layout::StylizeParams& p, bool& built) {
    std::string key = "stylizer-light/" + std::to_string(gpu.extinctionVersion()) + "/" + std::to_string(n.x) + "x" + std::to_string(n.y) + "x" + std::to_string(n.z);
    for (double x : {v.extinctionScale, v.lo.x, v.lo.y, v.lo.z, v.hi.x, v.hi.y, v.hi.z, double(p.options.z), double(p.lightDirection.x), double(p.lightDirection.y),
                     double(p.lightDirection.z), double(p.spot.x), double(p.spot.y), double(p.spot.z)})
        key += "/" + exact(x);
    if (auto cached = device.cache().find<DerivedGrid>(key)) return cached;
    DerivedGrid made{texture3D(n, nullptr, "stylizer-light-optical-depth"), {}};
    device.setParams(p);
    glUseProgram(device.program(gl::ShaderBuilder("stylize_transmittance.comp")).id());
    glBindImageTexture(layout::kImageUnitOut, made.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatchOver(n);
    built = true;
    return device.cache().insert(key, std::make_shared<const DerivedGrid>(std::move(made)));
}

}  // namespace

int stylizerMediumBlock(Int3 dims, int64_t maxVoxels) {
    int block = 1;
    while (int64_t(ceilDiv(dims, block).volume()) > std::max<int64_t>(maxVoxels, 1)) ++block;
    return block;
}

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
    const int block = gpu->isSparse() ? stylizerMediumBlock(gpu->dims(), v.maxSparseMediumVoxels) : 1;
    const std::shared_ptr<const DerivedGrid> sigma = meanExtinction(device, *gpu, block, built);
    glBindTextureUnit(layout::kUnitStylizeDensity, sigma->texture.id());
    glBindTextureUnit(layout::kUnitStylizeOccupancy, sigma->occupancy ? sigma->occupancy.id() : gpu->occupancyTexture());
    std::shared_ptr<const DerivedGrid> depth;
    if (v.lightTransmittance) depth = lightOpticalDepth(device, v, *gpu, ceilDiv(gpu->dims(), block), p, built);
    glBindTextureUnit(layout::kUnitStylizeTransmittance, depth ? depth->texture.id() : gpu->extinctionTexture());  // off: unread
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory for the stylizer's volume");
    if (!built) return 0;
    device.finish();
    return msSince(t0);
}

}  // namespace volstyle::core

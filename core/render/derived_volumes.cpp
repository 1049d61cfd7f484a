#include "core/render/derived_volumes.h"

#include <fmt/format.h>

#include "core/base/stopwatch.h"
#include "core/render/chunked_dispatch.h"
#include "core/render/gl_convert.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

layout::MarchParams volumeParams(const GpuVolume& volume, const RenderSettings& settings) {
    layout::MarchParams p;
    p.indexFromWorld = toGl(volume.worldFromIndex().inverseAffine());
    p.dims = i4(volume.dims());
    p.brickDims = i4(volume.brickDims());
    p.march = {float(settings.stepVoxels), float(settings.terminationThreshold), 0, 0};
    return p;
}

void dispatch3D(Int3 n) {
    const int g = layout::kWorkgroup3D;
    glDispatchCompute(GLuint((n.x + g - 1) / g), GLuint((n.y + g - 1) / g), GLuint((n.z + g - 1) / g));
}

void updateOccupancy(GpuDevice& device, GpuVolume& volume, RenderStats& stats) {
    if (volume.occupancyVersion() == volume.extinctionVersion()) return;
    const auto t0 = Clock::now();
    device.setParams(volumeParams(volume, RenderSettings{}));
    glUseProgram(device.program(gl::ShaderBuilder("occupancy.comp")).id());
    glBindTextureUnit(layout::kUnitExtinction, volume.extinctionTexture());
    glBindImageTexture(layout::kImageUnitOut, volume.occupancyTexture(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatch3D(volume.brickDims());
    gl::barrierAfterComputeWrites();
    volume.markOccupancyCurrent();
    device.finish();  // rare: wait so the timing is this pass's own
    stats.occupancyMs += msSince(t0);
}

std::string lightDepthKey(const GpuVolume& volume, const Vec3d& direction, const RenderSettings& march) {
    const Mat4& m = volume.worldFromIndex();
    std::string key = fmt::format("light-depth:{}:{}x{}x{}:{},{},{}:{}:{}:", volume.extinctionVersion(), volume.dims().x,
                                  volume.dims().y, volume.dims().z, direction.x, direction.y, direction.z,
                                  march.stepVoxels, march.exactTraversal ? "exact" : "march");
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) key += fmt::format("{},", m(r, c));  // shortest round-trip: exact
    return key;
}

std::shared_ptr<const gl::Texture> lightDepthVolume(GpuDevice& device, const GpuVolume& volume, const DirectionalLight& light,
                                                    const RenderSettings& march, RenderStats& stats,
                                                    const WorkBudget& budget) {
    const Vec3d dir = normalize(light.direction);
    const std::string key = lightDepthKey(volume, dir, march);
    if (auto cached = device.cache().find<gl::Texture>(key)) return cached;

    const auto t0 = Clock::now();
    auto texture = std::make_shared<gl::Texture>(gl::createTexture(GL_TEXTURE_3D, "light-depth"));
    const Int3 d = volume.dims();
    glTextureStorage3D(texture->id(), 1, GL_RGBA32F, d.x, d.y, d.z);
    RenderSettings settings;
    settings.stepVoxels = march.stepVoxels;
    layout::MarchParams p = volumeParams(volume, settings);
    p.lightKernel = {0, 0, 0, 0};
    p.lightDirection[0] = f4(dir);
    glUseProgram(device.program(gl::ShaderBuilder("light_depth.comp")
                                    .define("VOLSTYLE_EXACT_TRAVERSAL", march.exactTraversal ? 1 : 0))
                     .id());
    glBindTextureUnit(layout::kUnitExtinction, volume.extinctionTexture());
    glBindTextureUnit(layout::kUnitOccupancy, volume.occupancyTexture());
    glBindImageTexture(layout::kImageUnitOut, texture->id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatchChunked(device, p, d, DispatchShape::Volume, budget, "light-depth pass");
    gl::barrierAfterComputeWrites();
    device.finish();  // rare: wait so the timing is this pass's own
    stats.lightMs += msSince(t0);
    stats.lightVolumesRecomputed++;
    return device.cache().insert<gl::Texture>(key, std::move(texture));
}

namespace {

double maxValue(const Image& image) {
    double m = 0;
    for (size_t i = 0; i < image.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) m = std::max(m, double(image.rgba[4 * i + c]));
    return m;
}

}  // namespace

std::shared_ptr<const EnvironmentTexture> environmentTexture(GpuDevice& device, const std::shared_ptr<const Image>& image) {
    const std::string key = fmt::format("environment:{}", static_cast<const void*>(image.get()));
    if (auto cached = device.cache().find<EnvironmentTexture>(key)) return cached;
    auto env = std::make_shared<EnvironmentTexture>();
    env->source = image;
    env->maxValue = maxValue(*image);
    env->texture = gl::createTexture(GL_TEXTURE_2D, "environment");
    const GLuint id = env->texture.id();
    glTextureStorage2D(id, 1, GL_RGBA32F, image->width, image->height);
    glTextureSubImage2D(id, 0, 0, 0, image->width, image->height, GL_RGBA, GL_FLOAT, image->rgba.data());
    glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(id, GL_TEXTURE_WRAP_S, GL_REPEAT);        // longitude wraps
    glTextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);  // poles clamp
    return device.cache().insert<EnvironmentTexture>(key, std::move(env));
}

}  // namespace volstyle::core

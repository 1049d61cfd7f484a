#include "core/render/derived_volumes.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/base/errors.h"
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
    p.sparseOffset = i4(volume.sparseOffset());
    return p;
}

gl::ShaderBuilder& forStorage(gl::ShaderBuilder& builder, const GpuVolume& volume) {
    if (volume.isSparse()) builder.define("VOLSTYLE_SPARSE", 1);
    return builder;
}

void bindExtinction(const GpuVolume& volume) {
    glBindTextureUnit(layout::kUnitExtinction, volume.extinctionTexture());
    glBindTextureUnit(layout::kUnitOccupancy, volume.occupancyTexture());
    if (volume.isSparse()) glBindTextureUnit(layout::kUnitBrickTable, volume.brickTableTexture());
}

void dispatch3D(Int3 n) {
    const int g = layout::kWorkgroup3D;
    glDispatchCompute(GLuint((n.x + g - 1) / g), GLuint((n.y + g - 1) / g), GLuint((n.z + g - 1) / g));
}

void updateOccupancy(GpuDevice& device, GpuVolume& volume, RenderStats& stats) {
    if (volume.occupancyVersion() == volume.extinctionVersion()) return;
    const auto t0 = Clock::now();
    device.setParams(volumeParams(volume, RenderSettings{}));
    glUseProgram(device.program(forStorage(gl::ShaderBuilder("occupancy.comp"), volume)).id());
    bindExtinction(volume);
    glBindImageTexture(layout::kImageUnitOut, volume.occupancyTexture(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatch3D(volume.brickDims());
    gl::barrierAfterComputeWrites();
    volume.markOccupancyCurrent();
    device.finish();  // rare: wait so the timing is this pass's own
    stats.occupancyMs += msSince(t0);
}

std::string extinctionKey(const GpuVolume& volume) {
    const Mat4& m = volume.worldFromIndex();
    std::string key = fmt::format("{}:{}x{}x{}:", volume.extinctionVersion(), volume.dims().x, volume.dims().y, volume.dims().z);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) key += fmt::format("{},", m(r, c));  // shortest round-trip: exact
    return key;
}

std::string lightDepthKey(const GpuVolume& volume, const Vec3d& direction, const RenderSettings& march) {
    return fmt::format("light-depth:{}:{},{},{}:{}", extinctionKey(volume), direction.x, direction.y, direction.z, march.stepVoxels);
}

std::shared_ptr<LightDepthVolume> computeLightDepth(GpuDevice& device, const GpuVolume& volume, const Vec3d& towardLight,
                                                   const RenderSettings& march, RenderStats& stats, const WorkBudget& budget,
                                                   double across) {
    const Vec3d dir = normalize(towardLight);
    const auto t0 = Clock::now();
    auto result = std::make_shared<LightDepthVolume>();
    const Mat4 indexFromWorld = volume.worldFromIndex().inverseAffine();
    if (volume.isSparse()) {
        // Only the active region (and a voxel around it) can hold extinction: the grid covers that,
        // with nodes spaced wider where it would be over kMaxSparseLightNodes.
        const auto [lo, hi] = volume.activeBox();
        const Vec3d a(lo.x - 0.5, lo.y - 0.5, lo.z - 0.5), b(hi.x + 0.5, hi.y + 0.5, hi.z + 0.5);
        double along = kLightGridSpacing;
        const double nodes = double(makeLightGrid(a, b, indexFromWorld, dir, across, along).dims.volume());
        if (nodes > kMaxSparseLightNodes) {
            const double widen = std::cbrt(nodes / kMaxSparseLightNodes);
            across *= widen, along *= widen;
        }
        result->grid = makeLightGrid(a, b, indexFromWorld, dir, across, along);
    } else {
        result->grid = makeLightGrid(volume.dims(), indexFromWorld, dir, across);
    }
    const Int3 n = result->grid.dims;
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &maxSize);
    if (n.x > maxSize || n.y > maxSize || n.z > maxSize)
        throw GpuError(fmt::format("a light-depth grid of {}x{}x{} exceeds this GPU's 3D texture limit of {}", n.x, n.y,
                                   n.z, maxSize));
    const bool grey = volume.extinctionIsGrey();
    result->texture = gl::createTexture(GL_TEXTURE_3D, "light-depth");
    const GLuint id = result->texture.id();
    glTextureStorage3D(id, 1, grey ? GL_R32F : GL_RGBA32F, n.x, n.y, n.z);
    if (grey)
        for (GLenum c : {GL_TEXTURE_SWIZZLE_G, GL_TEXTURE_SWIZZLE_B}) glTextureParameteri(id, c, GL_RED);
    // Clamp-to-edge linear sampling for the hardware-filter variant (texelFetch ignores it).
    glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R}) glTextureParameteri(id, wrap, GL_CLAMP_TO_EDGE);

    const float zero[4] = {0, 0, 0, 0};
    glClearTexImage(id, 0, grey ? GL_RED : GL_RGBA, GL_FLOAT, zero);  // light_depth.comp writes from where rows enter

    RenderSettings settings;
    settings.stepVoxels = march.stepVoxels;
    layout::MarchParams p = volumeParams(volume, settings);
    p.lightKernel = {0, 0, 0, 0};
    p.lightGridDims[0] = i4(n);
    p.indexFromLightGrid = toGl(result->grid.indexFromGrid);
    glUseProgram(device.program(forStorage(gl::ShaderBuilder("light_depth.comp").define("VOLSTYLE_GREY_DEPTH", grey ? 1 : 0), volume)).id());
    bindExtinction(volume);
    glBindImageTexture(layout::kImageUnitOut, id, 0, GL_TRUE, 0, GL_WRITE_ONLY, grey ? GL_R32F : GL_RGBA32F);
    // A row of n.z nodes costs about as much as n.z / 4 per-pixel or per-voxel invocations (two
    // samples per node, most in empty bricks): chunks of about the same time as other passes'.
    dispatchChunked(device, p, {n.x, n.y, 1}, DispatchShape::Image, budget, "light-depth pass",
                    std::max(1LL, kChunkInvocations / std::max(1, n.z / 4)));
    gl::barrierAfterComputeWrites();
    device.finish();  // rare: wait so the timing is this pass's own
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory building a light-depth volume");
    stats.lightMs += msSince(t0);
    stats.lightVolumesRecomputed++;
    return result;
}

std::shared_ptr<const LightDepthVolume> lightDepthVolume(GpuDevice& device, const GpuVolume& volume,
                                                         const DirectionalLight& light, const RenderSettings& march,
                                                         RenderStats& stats, const WorkBudget& budget) {
    const std::string key = lightDepthKey(volume, normalize(light.direction), march);
    if (auto cached = device.cache().find<LightDepthVolume>(key)) return cached;
    const double across = lightGridAcross(maxVoxelDepth(volume.maxExtinction(), volume.worldFromIndex()));
    return device.cache().insert<LightDepthVolume>(key, computeLightDepth(device, volume, light.direction, march, stats, budget, across));
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

#include "core/stylize/medium_gpu.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

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

Int3 brickDims(Int3 n) {
    const int b = layout::kStylizeBrick;
    return {(n.x + b - 1) / b, (n.y + b - 1) / b, (n.z + b - 1) / b};
}

/// Per brick, the largest σt of the voxels a trilinear lookup inside it can read: the brick and
/// one voxel around it (0: the march may skip it).
std::vector<float> brickMaxima(const std::vector<float>& sigma, Int3 n) {
    const Int3 nb = brickDims(n);
    const int b = layout::kStylizeBrick;
    std::vector<float> out(size_t(nb.volume()), 0.0f);
    for (int k = 0; k < n.z; ++k)
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
                const float v = sigma[(size_t(k) * size_t(n.y) + size_t(j)) * size_t(n.x) + size_t(i)];
                if (v <= 0) continue;
                // Every brick whose dilated box [8B − 1, 8B + 8] holds voxel (i, j, k).
                for (int bk = std::max(0, (k - 1) / b); bk <= std::min(nb.z - 1, (k + 1) / b); ++bk)
                    for (int bj = std::max(0, (j - 1) / b); bj <= std::min(nb.y - 1, (j + 1) / b); ++bj)
                        for (int bi = std::max(0, (i - 1) / b); bi <= std::min(nb.x - 1, (i + 1) / b); ++bi) {
                            float& m = out[(size_t(bk) * size_t(nb.y) + size_t(bj)) * size_t(nb.x) + size_t(bi)];
                            m = std::max(m, v);
                        }
            }
    return out;
}

}  // namespace

namespace {

/// A number exactly, for a cache key.
std::string exact(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%a", v);
    return buf;
}

struct MediumTextures {
    gl::Texture density, occupancy;
};

struct LightOpticalDepth {
    gl::Texture texture;
};

/// The optical depth toward the light per voxel (stylize_transmittance.comp), from the device's
/// cache when the grid, its scale, box and the light are the same; `built` when it was made.
std::shared_ptr<const LightOpticalDepth> lightOpticalDepth(GpuDevice& device, const StylizerVolume& v, const std::string& densityKey,
                                                           layout::StylizeParams& p, bool& built) {
    std::string key = "stylizer-light/" + densityKey;
    for (double x : {v.lo.x, v.lo.y, v.lo.z, v.hi.x, v.hi.y, v.hi.z, double(p.options.z), double(p.lightDirection.x), double(p.lightDirection.y),
                     double(p.lightDirection.z), double(p.spot.x), double(p.spot.y), double(p.spot.z)})
        key += "/" + exact(x);
    if (auto cached = device.cache().find<LightOpticalDepth>(key)) return cached;
    const Int3 n = v.grid->dims;
    LightOpticalDepth made{texture3D(n, nullptr, "stylizer-light-optical-depth")};
    device.setParams(p);
    glUseProgram(device.program(gl::ShaderBuilder("stylize_transmittance.comp")).id());
    glBindImageTexture(layout::kImageUnitOut, made.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    const int g = layout::kWorkgroup3D;
    glDispatchCompute(GLuint((n.x + g - 1) / g), GLuint((n.y + g - 1) / g), GLuint((n.z + g - 1) / g));
    gl::barrierAfterComputeWrites();
    built = true;
    return device.cache().insert(key, std::make_shared<const LightOpticalDepth>(std::move(made)));
}

}  // namespace

double bindStylizerMedium(GpuDevice& device, const std::optional<StylizerVolume>& volume, layout::StylizeParams& p) {
    p.volumeLo = {0, 0, 0, 0};
    p.volumeHi = {1, 1, 1, 0};
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
    const auto t0 = Clock::now();
    const StylizerVolume& v = *volume;
    const Int3 n = v.grid->dims;
    p.volumeLo = {float(v.lo.x), float(v.lo.y), float(v.lo.z), float(v.steps)};
    p.volumeHi = {float(v.hi.x), float(v.hi.y), float(v.hi.z), v.lightTransmittance ? 1.0f : 0.0f};
    bool built = false;
    // σt and its bricks' maxima: one entry per grid and scale.
    const std::string densityKey = "stylizer-medium/" + std::to_string(v.grid->id) + "/" + exact(v.extinctionScale);
    auto medium = cache.find<MediumTextures>(densityKey);
    if (!medium) {
        std::vector<float> sigma(v.grid->sigma);
        for (float& s : sigma) s = float(s * v.extinctionScale);
        MediumTextures made{texture3D(n, sigma.data(), "stylizer-density"), {}};
        const std::vector<float> bricks = brickMaxima(sigma, n);
        made.occupancy = texture3D(brickDims(n), bricks.data(), "stylizer-occupancy");
        glTextureParameteri(made.occupancy.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(made.occupancy.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        medium = cache.insert(densityKey, std::make_shared<const MediumTextures>(std::move(made)));
        built = true;
    }
    glBindTextureUnit(layout::kUnitStylizeDensity, medium->density.id());
    glBindTextureUnit(layout::kUnitStylizeOccupancy, medium->occupancy.id());
    std::shared_ptr<const LightOpticalDepth> depth;
    if (v.lightTransmittance) depth = lightOpticalDepth(device, v, densityKey, p, built);
    glBindTextureUnit(layout::kUnitStylizeTransmittance, depth ? depth->texture.id() : medium->density.id());  // off: unread
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory for the stylizer's volume");
    if (!built) return 0;
    device.finish();
    return msSince(t0);
}

}  // namespace volstyle::core

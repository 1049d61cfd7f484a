#include "core/render/lobe_volumes.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/gl/shader_builder.h"
#include "core/render/chunked_dispatch.h"
#include "core/render/derived_volumes.h"
#include "core/render/gl_convert.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

static_assert(layout::kMaxLobeSlots == kMaxLobes, "LobeParams holds every lobe");

std::shared_ptr<const LobeLightVolumes> lobeLightVolumes(GpuDevice& device, GpuVolume& volume, const LobeBasis& basis,
                                                         int resolution, const RenderSettings& march, RenderStats& stats,
                                                         const WorkBudget& budget) {
    const Int3 dims = lobeGridDims(volume.dims(), resolution);
    // By the extinction's content, not its GpuVolume's version: every solve uploads its own copy,
    // and N light-depth passes are worth not repeating for the same grid.
    std::string grid = fmt::format("{:x}:{}x{}x{}:", volume.extinctionHash(), volume.dims().x, volume.dims().y, volume.dims().z);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) grid += fmt::format("{},", volume.worldFromIndex()(r, c));
    const std::string key = fmt::format("lobe-volumes:{}:{}:{}x{}x{}:{}", grid, basis.key(), dims.x, dims.y, dims.z, march.stepVoxels);
    if (auto cached = device.cache().find<LobeLightVolumes>(key)) return cached;

    auto result = std::make_shared<LobeLightVolumes>();
    result->dims = dims;
    result->lobes = basis.size();
    result->channels = volume.extinctionIsGrey() ? 1 : 3;
    GLint maxTexels = 0;
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &maxTexels);
    const size_t texels = result->bytes() / sizeof(float);
    if (texels > size_t(maxTexels) || result->bytes() > kMaxLobeVolumeBytes)
        throw LimitExceeded(fmt::format(
            "environment: {} light volumes of {}x{}x{} nodes need {} MiB (at most {} MiB and {} million values on this GPU); "
            "lower lobes or light_volume_resolution",
            basis.size(), dims.x, dims.y, dims.z, result->bytes() >> 20, kMaxLobeVolumeBytes >> 20, maxTexels / 1000000));
    updateOccupancy(device, volume, stats);
    result->storage = gl::createBuffer(result->bytes(), nullptr, 0, "lobe-light-volumes");
    result->texture = gl::createTexture(GL_TEXTURE_BUFFER, "lobe-light-volumes");
    glTextureBuffer(result->texture.id(), GL_R32F, result->storage.id());

    const auto t0 = Clock::now();
    RenderStats depthStats;
    for (int lobe = 0; lobe < basis.size(); ++lobe) {
        budget.check("environment light volumes", double(lobe) / basis.size());
        const auto depth = computeLightDepth(device, volume, basis.directions[size_t(lobe)], march, depthStats, budget);
        layout::MarchParams p = volumeParams(volume, march);
        p.lightGridFromIndex[0] = toGl(depth->grid.gridFromIndex);
        p.lightGridDims[0] = i4(depth->grid.dims);
        p.lobeGrid = {dims.x, dims.y, dims.z, basis.size()};
        p.lobeScale = {float(dims.x) / float(volume.dims().x), float(dims.y) / float(volume.dims().y),
                       float(dims.z) / float(volume.dims().z), float(result->channels)};
        p.lobeKernel = {lobe, 0, 0, 0};
        glUseProgram(device.program(forStorage(gl::ShaderBuilder("lobe_volume.comp"), volume)).id());
        glBindTextureUnit(layout::kUnitLightDepth0, depth->texture.id());
        glBindImageTexture(layout::kImageUnitOut, result->texture.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
        dispatchChunked(device, p, dims, DispatchShape::Volume, budget, "environment light volumes");
    }
    gl::barrierAfterComputeWrites();
    device.finish();
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory building the environment's light volumes");
    stats.lightMs += msSince(t0);
    stats.lightVolumesRecomputed += basis.size();
    return device.cache().insert<LobeLightVolumes>(key, std::move(result));
}

}  // namespace volstyle::core

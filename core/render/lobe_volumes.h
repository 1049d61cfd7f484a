#pragma once
/// \file lobe_volumes.h
/// The environment lobes' light volumes (SPEC §8; TVCG Sec. 5.3): for every lobe, the
/// transmittance toward it at the nodes of a grid of its own resolution that spans the voxels'
/// box (node j at extinction index (j + 0.5)/scale − 0.5, as the solver's unknown grids), read
/// trilinearly by the renderer and the lights projector (common/lobes.glsl). Each lobe's volume
/// is resampled from its light-depth pass (light_depth.comp, O(N) per lobe) by lobe_volume.comp.
/// Stored node-major, [node][lobe][channel], in one buffer texture, so a sample reads every lobe
/// of a node from one run of memory. Cached until the extinction, the basis, the resolution or
/// the step changes. GL thread only.

#include <memory>
#include <string>

#include "core/base/work_budget.h"
#include "core/gl/object.h"
#include "core/gpu/gpu_device.h"
#include "core/scene/environment_lobes.h"
#include "core/render/gpu_volume.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/render/render_stats.h"

namespace volstyle::core {

struct LobeLightVolumes {
    Int3 dims;         ///< nodes
    int lobes = 0;
    int channels = 1;  ///< 1 for grey extinction, 3 for rgb
    gl::Buffer storage;
    gl::Texture texture;  ///< R32F buffer texture over `storage`
    size_t bytes() const { return size_t(dims.volume()) * size_t(lobes) * size_t(channels) * sizeof(float); }
};

/// The light volumes of `basis` for `volume`, from the cache or computed now (one light-depth pass
/// and one resampling per lobe, checked against `budget` between lobes). Throws LimitExceeded when
/// they would not fit in a buffer texture or in kMaxLobeVolumeBytes.
std::shared_ptr<const LobeLightVolumes> lobeLightVolumes(GpuDevice& device, GpuVolume& volume, const LobeBasis& basis,
                                                         int resolution, const RenderSettings& march, RenderStats& stats,
                                                         const WorkBudget& budget = WorkBudget());
constexpr size_t kMaxLobeVolumeBytes = size_t(2) << 30;

}  // namespace volstyle::core

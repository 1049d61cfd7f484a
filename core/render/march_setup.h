#pragma once
/// \file march_setup.h
/// What every march kernel shares (the renderer's render.comp, the solver's project.comp and the
/// engines to come): the uniform block for a camera, and the derived volumes a ray reads —
/// occupancy bricks, a light-depth volume per lit light, the environment texture. The derived
/// volumes come from the device's cache and are held by the MarchSetup, so nothing else on the
/// device (another session's render, an eviction) can free or replace what it binds.
/// GL thread only.

#include <memory>
#include <vector>

#include "core/base/work_budget.h"
#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/gpu/gpu_device.h"
#include "core/render/derived_volumes.h"
#include "core/render/gpu_volume.h"
#include "core/render/lobe_volumes.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/render/refracted_paths.h"
#include "core/render/render_stats.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

struct MarchSetup {
    layout::MarchParams params;
    /// Light-depth volumes of the lights with non-zero irradiance, in lightDirection[] order.
    std::vector<std::shared_ptr<const LightDepthVolume>> lightDepth;
    std::shared_ptr<const gl::Texture> environment;  ///< null without an environment map or plate
    bool plate = false;  ///< `environment` is the view's plate (Background::plate), read per pixel
    bool backgroundLobes = false;  ///< the lobes seen directly are the background (lobeParams bound)
    /// The environment's lobes when they light the medium (null otherwise: no lobes, or all dark),
    /// and their directions, solid angles and radiances.
    std::shared_ptr<const LobeLightVolumes> lobes;
    layout::LobeParams lobeParams;
    /// The camera's rays bent by the volume's refractive index, or null: straight rays.
    std::shared_ptr<const RefractedPaths> paths;
};

/// Updates occupancy if stale, finds or computes the derived volumes, fills the uniform block.
/// Light-depth passes run under `budget` (OverBudget or Cancelled between chunks).
MarchSetup prepareMarch(GpuDevice& device, GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                        const RenderSettings& settings, RenderStats& stats, const WorkBudget& budget = WorkBudget());
/// Uploads the blocks and binds extinction, occupancy, environment, light-depth and lobe textures.
void bindMarch(GpuDevice& device, const GpuVolume& volume, const MarchSetup& setup);

}  // namespace volstyle::core

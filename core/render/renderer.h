#pragma once
/// \file renderer.h
/// The single-scattering renderer on GL compute (SPEC §1). Derived data (occupancy, light-depth
/// volumes, environment textures) is shared through the device and recomputed only when what it
/// depends on changes (march_setup.h). GL thread only; GL-free header.

#include <memory>

#include "core/base/work_budget.h"
#include "core/gpu/gpu_device.h"
#include "core/image/image.h"
#include "core/render/gpu_volume.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/render/render_stats.h"

namespace volstyle::core {

/// A render split for compositing (issue #10), every image linear RGBA at the camera's size.
/// `medium` over a plate B gives the render in front of B: medium + (1 − alpha)·B (exact for a
/// grey transmittance; per channel, use `transmittance`: medium + transmittance·B).
struct RenderLayers {
    Image beauty;         ///< the render as render() gives it: medium + transmittance·background
    Image medium;         ///< the medium's light alone, premultiplied; alpha = 1 − mean transmittance
    Image emission;       ///< the part of `medium` the medium emits
    Image scattering;     ///< the part of `medium` scattered from the lights
    Image transmittance;  ///< RGB transmittance along each ray (alpha 1)
    Image background;     ///< the background's radiance, unattenuated (alpha 1)
    /// The scattering the same rays give at albedo 1 (renderLayers' withAlbedoOne), else empty:
    /// what an albedo solve could reach, with no second render of a white volume.
    Image scatteringAtAlbedoOne;
};

class Renderer {
public:
    explicit Renderer(GpuDevice& device);
    ~Renderer();

    /// Renders linear RGBA (alpha = 1 − mean transmittance). Throws InvalidArgument for an
    /// invalid camera, lighting or settings; OverBudget or Cancelled when `budget` runs out
    /// (checked between chunks of the light-depth passes and the march; nothing half-made is kept).
    Image render(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                 const RenderSettings& settings = {}, RenderStats* stats = nullptr,
                 const WorkBudget& budget = WorkBudget());

    /// The same render, with its compositing layers.
    RenderLayers renderLayers(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                              const RenderSettings& settings = {}, RenderStats* stats = nullptr,
                              const WorkBudget& budget = WorkBudget(), bool withAlbedoOne = false);

private:
    Image march(GpuVolume& volume, const Camera& camera, const Lighting& lighting, const RenderSettings& settings,
                RenderStats* stats, const WorkBudget& budget, RenderLayers* layers, bool withAlbedoOne = false);

    struct Buffers;
    GpuDevice& m_device;
    std::unique_ptr<Buffers> m_buffers;
};

}  // namespace volstyle::core

#pragma once
/// \file renderer.h
/// The single-scattering renderer on GL compute (SPEC §1). Derived data (occupancy, light-depth
/// volumes, environment textures) is shared through the device and recomputed only when what it
/// depends on changes (march_setup.h). GL thread only; GL-free header.

#include <memory>

#include "core/gpu/gpu_device.h"
#include "core/image/image.h"
#include "core/render/gpu_volume.h"
#include "core/render/params.h"
#include "core/render/render_stats.h"

namespace volstyle::core {

class Renderer {
public:
    explicit Renderer(GpuDevice& device);
    ~Renderer();

    /// Renders linear RGBA (alpha = 1 − mean transmittance). Throws InvalidArgument for an
    /// invalid camera, lighting or settings.
    Image render(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                 const RenderSettings& settings = {}, RenderStats* stats = nullptr);

private:
    struct Buffers;
    GpuDevice& m_device;
    std::unique_ptr<Buffers> m_buffers;
};

}  // namespace volstyle::core

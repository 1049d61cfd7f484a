#pragma once
/// \file renderer.h
/// The single-scattering renderer on GL compute (SPEC §1). Derived data (occupancy, light-depth
/// volumes, environment textures) is shared through the device and recomputed only when what it
/// depends on changes (march_setup.h). GL thread only.

#include "core/gl/object.h"
#include "core/gpu/gpu_device.h"
#include "core/image/image.h"
#include "core/render/gpu_volume.h"
#include "core/render/march_setup.h"
#include "core/render/params.h"

namespace volstyle::core {

class Renderer {
public:
    explicit Renderer(GpuDevice& device);

    /// Renders linear RGBA (alpha = 1 − mean transmittance). Throws InvalidArgument for an
    /// invalid camera, lighting or settings.
    Image render(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                 const RenderSettings& settings = {}, RenderStats* stats = nullptr);

private:
    GpuDevice& m_device;
    gl::Buffer m_pixels;
    size_t m_pixelBytes = 0;
    gl::GpuTimer m_timer;
};

}  // namespace volstyle::core

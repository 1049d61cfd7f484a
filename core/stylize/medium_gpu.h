#pragma once
/// \file medium_gpu.h
/// The stylizer's heterogeneous medium on the GPU (issue #15): its σt grid as a 3D texture (scaled
/// by extinction_scale), its bricks' occupancy (empty space the march crosses in one step) and the optical depth toward the light per voxel
/// (stylize_transmittance.comp), kept while the grid, its scale, box and the light stay the same:
/// a live stream or a sequence re-renders the same medium with another camera or TF.
/// Internal to core (GL types). GL thread only.

#include <array>
#include <optional>
#include <tuple>

#include "core/gl/object.h"
#include "core/gpu/gpu_device.h"
#include "core/shaders/layout.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

class StylizerMediumCache {
public:
    /// Binds the medium's textures for stylize.comp and fills p.volumeLo/volumeHi (p's light
    /// fields already set); without a medium, binds 1³ placeholders and leaves it homogeneous.
    /// Returns the milliseconds spent building textures (0 when cached).
    double bind(GpuDevice& device, const std::optional<StylizerVolume>& volume, layout::StylizeParams& p);

private:
    using DensityKey = std::tuple<uint64_t, double>;
    /// The grid's id and scale, the box, the light's type, direction and position.
    using LightKey = std::array<double, 15>;
    gl::Texture m_density, m_occupancy, m_transmittance, m_empty;
    std::optional<DensityKey> m_densityKey;
    std::optional<LightKey> m_lightKey;
};

}  // namespace volstyle::core

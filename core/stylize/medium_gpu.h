#pragma once
/// \file medium_gpu.h
/// The stylizer's heterogeneous medium on the GPU (issue #15): its σt grid as a 3D texture (scaled
/// by extinction_scale), its bricks' occupancy (empty space the march crosses in one step) and the optical depth toward the light per voxel
/// (stylize_transmittance.comp), kept in the device's cache while the grid, its scale, box and the
/// light stay the same: a live stream or a sequence re-renders the same medium with another camera
/// or TF.
/// Internal to core (GL types). GL thread only.

#include <optional>

#include "core/gl/object.h"
#include "core/gpu/gpu_device.h"
#include "core/shaders/layout.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

/// Binds the medium's textures for stylize.comp and fills p.volumeLo/volumeHi (p's light fields
/// already set); without a medium, binds 1³ placeholders and leaves it homogeneous. The textures
/// live in the device's cache (keys: the grid's id and scale; for the light's optical depth also
/// the box and the light). Returns the milliseconds spent building textures (0 when cached).
double bindStylizerMedium(GpuDevice& device, const std::optional<StylizerVolume>& volume, layout::StylizeParams& p);

}  // namespace volstyle::core

#pragma once
/// \file medium_gpu.h
/// The stylizer's heterogeneous medium on the GPU (issue #15): the session's own GpuVolume (issue
/// #36: its RGB extinction texture and occupancy bricks, no copy), stretched over the scene's
/// box, and the optical depth toward the light per voxel (stylize_transmittance.comp), kept in
/// the device's cache while the volume's extinction, the scale, box and light stay the same: a
/// live stream or a sequence re-renders the same medium with another camera or TF.
/// A sparse volume's medium is the mean of its σt over blocks of voxels (one voxel each while its
/// box fits StylizerVolume::maxSparseMediumVoxels), with bricks of its own for skipping, so the
/// stylizer's memory and light pass stay bounded whatever the box.
/// Internal to core (GL types). GL thread only.

#include <optional>

#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/shaders/layout.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

/// The side of the blocks a sparse volume of `dims` voxels is averaged over for the stylizer's
/// medium (issue #39): the smallest that leaves at most `maxVoxels` (StylizerVolume::maxSparseMediumVoxels).
int stylizerMediumBlock(Int3 dims, int64_t maxVoxels);

/// Binds the medium's textures for stylize.comp and fills p.volumeLo/volumeHi/volumeScale (p's
/// light fields already set); without a medium, binds 1³ placeholders and leaves it
/// homogeneous. `gpu` is the volume whose extinction is the medium (required with `volume`; its
/// occupancy is brought up to date). Returns the milliseconds spent building (0 when cached).
double bindStylizerMedium(GpuDevice& device, const std::optional<StylizerVolume>& volume, GpuVolume* gpu, layout::StylizeParams& p);

}  // namespace volstyle::core

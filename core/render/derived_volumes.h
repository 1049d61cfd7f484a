#pragma once
/// \file derived_volumes.h
/// GPU data derived from a volume and the lighting, computed once and reused until what it
/// depends on changes: brick occupancy (kept in the GpuVolume), light-depth volumes and
/// environment textures (kept in the device's cache under keys naming every input).
/// GL thread only.

#include <memory>
#include <string>

#include "core/base/work_budget.h"
#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/render/light_grid.h"
#include "core/render/render_stats.h"
#include "core/shaders/layout.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"

namespace volstyle::core {

/// The kernel variant for the volume's storage: VOLSTYLE_SPARSE for a sparse volume (a dense
/// volume's kernel source is unchanged).
gl::ShaderBuilder& forStorage(gl::ShaderBuilder& builder, const GpuVolume& volume);
inline gl::ShaderBuilder forStorage(gl::ShaderBuilder&& builder, const GpuVolume& volume) { return std::move(forStorage(builder, volume)); }
/// Binds the volume's extinction and occupancy (and a sparse volume's brick table) to their units.
void bindExtinction(const GpuVolume& volume);

/// Recomputes the occupancy bricks (occupancy.comp) if the extinction changed since.
void updateOccupancy(GpuDevice& device, GpuVolume& volume, RenderStats& stats);

/// The part of a cache key that names the extinction grid: its version, dims and transform.
std::string extinctionKey(const GpuVolume& volume);

/// The cache key of a light-depth volume: everything light_depth.comp reads — the extinction
/// (its version), the grid (dims, transform), the light's direction and the step.
std::string lightDepthKey(const GpuVolume& volume, const Vec3d& direction, const RenderSettings& march);

/// The optical depth toward a light on the nodes of its light-aligned grid: R32F (swizzled to
/// grey) for grey extinction, RGBA32F otherwise.
struct LightDepthVolume {
    LightGrid grid;
    gl::Texture texture;
};

/// The light-depth volume toward `towardLight` (light_depth.comp), computed now and not cached
/// (the environment's lobes resample it into their light volumes and drop it).
/// `across`: voxels between the grid's rows across the beam (light_grid.h; lights take
/// lightGridAcross of the volume, the environment's lobes kLightGridSpacing).
std::shared_ptr<LightDepthVolume> computeLightDepth(GpuDevice& device, const GpuVolume& volume, const Vec3d& towardLight,
                                                   const RenderSettings& march, RenderStats& stats,
                                                   const WorkBudget& budget = WorkBudget(), double across = kLightGridSpacing);

/// The light-depth volume of `light` (light_depth.comp), from the cache or computed now, in
/// chunks checked against `budget` (a pass stopped early caches nothing). Needs current occupancy.
std::shared_ptr<const LightDepthVolume> lightDepthVolume(GpuDevice& device, const GpuVolume& volume,
                                                         const DirectionalLight& light, const RenderSettings& march,
                                                         RenderStats& stats, const WorkBudget& budget = WorkBudget());

/// An environment map on the GPU, and its largest value (for the early-termination bound).
struct EnvironmentTexture {
    std::shared_ptr<const Image> source;  ///< held so the key (its address) is never reused while cached
    gl::Texture texture;
    double maxValue = 0;
};
std::shared_ptr<const EnvironmentTexture> environmentTexture(GpuDevice& device, const std::shared_ptr<const Image>& image);

/// The MarchParams fields that depend only on the volume and the settings.
layout::MarchParams volumeParams(const GpuVolume& volume, const RenderSettings& settings);
/// One invocation per cell of `n`, in kWorkgroup3D³ groups.
void dispatch3D(Int3 n);

}  // namespace volstyle::core

#pragma once
/// \file refracted_paths.h
/// A view's refracted rays on the GPU (issue #16): curved_paths.h's polylines as two buffers the
/// march reads under VOLSTYLE_CURVED (common/march.glsl), traced once per (grid, camera, step)
/// and kept in the device's cache, so the solver's views and repeated renders reuse them.
/// GL thread only.

#include <memory>

#include "core/base/work_budget.h"
#include "core/gl/object.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/render/render_stats.h"

namespace volstyle::core {

struct RefractedPaths {
    gl::Buffer start;     ///< uint per pixel + 1 (layout::kBindingPathStart)
    gl::Buffer vertices;  ///< vec4 (index-space xyz, arc length t) (layout::kBindingPathVertex)
    gl::Buffer exits;     ///< vec4 per pixel: the world direction its ray leaves in (layout::kBindingPathExit)
    size_t vertexCount = 0;
    size_t bytes = 0;
    double traceMs = 0;
};

/// The paths of `camera`'s rays through the volume's refractive grid, or null when its rays are
/// straight (no grid, a constant one, or settings.refraction off): then nothing is traced.
std::shared_ptr<const RefractedPaths> refractedPaths(GpuDevice& device, const GpuVolume& volume, const Camera& camera,
                                                     const RenderSettings& settings, RenderStats& stats,
                                                     const WorkBudget& budget = WorkBudget());

/// Binds the paths for the march kernels.
void bindRefractedPaths(const RefractedPaths& paths);

}  // namespace volstyle::core

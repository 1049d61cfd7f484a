#pragma once
/// \file morphology_gpu.h
/// The GPU edits of morphology.h and shadow_edits.h on a depth map already in a buffer (n×n
/// floats), in place.
/// Internal to core (GL types). GL thread only.

#include "core/gl/object.h"
#include "core/gpu/gpu_device.h"
#include "core/stylize/morphology.h"
#include "core/stylize/shadow_edits.h"

namespace volstyle::core {

void closeDepthBuffer(GpuDevice& device, gl::Buffer& depth, int n, int radius, MorphShape shape);

/// A box erosion (maximum over (2r + 1)², the epipolar dilation's optional second step), in place.
void erodeBoxBuffer(GpuDevice& device, gl::Buffer& depth, int n, int radius);

/// Eq. 3's epipolar dilation (shadow_dilate.comp) and Eq. 4's holes (shadow_holes.comp), in place.
void dilateEpipolarBuffer(GpuDevice& device, gl::Buffer& depth, int n, const Epipole& e, int kernelTexels);
void cutHolesBuffer(GpuDevice& device, gl::Buffer& depth, int n, const HoleMap& h);

/// into = min(into, from), texel by texel (composites an object's manipulated shadow).
void foldMinimum(GpuDevice& device, const gl::Buffer& from, const gl::Buffer& into, int n);

}  // namespace volstyle::core

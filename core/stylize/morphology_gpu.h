#pragma once
/// \file morphology_gpu.h
/// The GPU closing of morphology.h on a depth map already in a buffer (n×n floats), in place.
/// Internal to core (GL types). GL thread only.

#include "core/gl/object.h"
#include "core/gpu/gpu_device.h"
#include "core/stylize/morphology.h"

namespace volstyle::core {

void closeDepthBuffer(GpuDevice& device, gl::Buffer& depth, int n, int radius, MorphShape shape);

/// into = min(into, from), texel by texel (composites an object's manipulated shadow).
void foldMinimum(GpuDevice& device, const gl::Buffer& from, const gl::Buffer& into, int n);

}  // namespace volstyle::core

#pragma once
/// \file morphology.h
/// Hole filling on shadow maps (the GI paper Sec. 4.1, SPEC §7 `closing`): a closing — a
/// dilation of the occluders (the minimum depth over the structuring element) then an erosion
/// (the maximum) — of an n×n depth map, with a box or a disc of radius r texels. Outside the map
/// is empty (depth 1): the stylizer leaves a margin of r texels around the occluders so that the
/// closing of what it draws is exact. GL-free header: the GPU version runs shadow_morphology.comp, the CPU one is
/// the brute-force reference the tests compare it with.
///
/// Cost on the GPU: a box is separable, one pass along rows and one along columns per operation,
/// each O(1) per texel whatever r (van Herk / Gil-Werman). A disc is the union of its 2r + 1 rows:
/// O(r) per texel (each row an O(1) running extremum), against O(r²) for a direct disc.

#include <vector>

#include "core/gpu/gpu_device.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

/// The half-width of a disc of radius r on row offset dy: the texels (dx, dy) with dx² + dy² ≤ r².
int discHalfWidth(int radius, int dy);

/// Brute force: for every texel the extremum over the element, clipped to the map.
std::vector<float> closingReference(const std::vector<float>& depth, int n, int radius, MorphShape shape);

/// The same on the GPU (uploads, runs the passes, reads back). radius 0 returns the input.
std::vector<float> closingOnGpu(GpuDevice& device, const std::vector<float>& depth, int n, int radius, MorphShape shape);

}  // namespace volstyle::core

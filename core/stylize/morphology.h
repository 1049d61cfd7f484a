#pragma once
/// \file morphology.h
/// Hole filling on shadow maps (the GI paper Sec. 4.1, SPEC §7 `closing`): a closing — a
/// dilation of the occluders (the minimum depth over the structuring element) then an erosion
/// (the maximum) — of an n×n depth map, with a box or a disc of radius r texels. Outside the map
/// is empty (depth 1): the stylizer leaves a margin of r texels around the occluders so that the
/// closing of what it draws is exact. GL-free header: the GPU version runs shadow_morphology.comp, the CPU one is
/// the brute-force reference the tests compare it with.
///
/// Cost on the GPU: every pass is a 1D running extremum along rows, columns or diagonals, O(1)
/// per texel whatever its length (van Herk / Gil-Werman). A box is separable: rows then columns.
/// A disc of radius r ≤ kExactDiscRadius is exact, the union of its 2r + 1 rows (O(r), small);
/// from r = 5 on it is the regular octagon of the same radius — the Minkowski sum of a square of
/// half-side a and diagonal segments of half-length b, a + 2b = r, b = round(r (1 − 1/√2)) —
/// four passes whatever r (the paper's Table 2 grows with the kernel's area). The octagon's
/// boundary is within 0.09 r of the disc's (its diagonal corners reach (a + b)√2 ≈ 1.01 r).

#include <vector>

#include "core/gpu/gpu_device.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

/// The half-width of a disc of radius r on row offset dy: the texels (dx, dy) with dx² + dy² ≤ r².
int discHalfWidth(int radius, int dy);

/// Discs up to this radius are exact; larger ones are octagons (above).
constexpr int kExactDiscRadius = 4;
struct Octagon {
    int a, b;  ///< the square's half-side and the diagonal segments' half-length
};
Octagon octagonOf(int radius);

/// The structuring element's half-width on row offset dy (−1 outside it): what the CPU reference
/// takes the extremum over.
int elementHalfWidth(int radius, int dy, MorphShape shape);

/// Brute force: for every texel the extremum over the element, clipped to the map.
std::vector<float> closingReference(const std::vector<float>& depth, int n, int radius, MorphShape shape);

/// The same on the GPU (uploads, runs the passes, reads back). radius 0 returns the input.
std::vector<float> closingOnGpu(GpuDevice& device, const std::vector<float>& depth, int n, int radius, MorphShape shape);

}  // namespace volstyle::core

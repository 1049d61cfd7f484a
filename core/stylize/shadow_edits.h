#pragma once
/// \file shadow_edits.h
/// The stylizer's per-object edits of a shadow map beyond the closing (the GI paper Sec. 4):
/// the 1D epipolar dilation of Eq. 3 and the Perlin-noise holes of Eq. 4–5, as CPU references
/// (tests) and GPU passes (shadow_edits_gpu.h). Maps are n×n floats, row 0 at the bottom,
/// depth in [0, 1], 1 = nothing. GL-free.

#include <cstdint>
#include <vector>

namespace volstyle::core {

/// The camera projected into the map: texel coordinates, depth, and the sense of the extrusion
/// (+1 away from the epipole; −1 when the camera is behind a spot light's plane).
struct Epipole {
    double x = 0, y = 0, depth = 0;
    double sense = 1;
};

/// Eq. 3 on the CPU: the same samples and arithmetic as shadow_dilate.comp.
std::vector<float> epipolarDilationReference(const std::vector<float>& depth, int n, const Epipole& e, int kernelTexels);

/// What shadow_holes.comp needs: where texels sit in noise coordinates, the threshold h
/// (holes where N < h), the time offset of the first lookup and the noise's shape.
struct HoleMap {
    double originX = 0, originY = 0;  ///< noise coordinates of texel (0, 0)'s corner
    double stepX = 1, stepY = 1;      ///< per texel
    float threshold = 0;
    double offsetX = 0, offsetY = 0;
    int octaves = 5;
    double persistence = 0.5;
    uint32_t seed = 1;
};

/// h such that a share `probability` of the noise's values lie below it: the quantile of 2^16
/// samples of holeNoise over a 64 × 64-unit square at time 0 (the noise is stationary, so the
/// share holds at every time and place; ±1% over areas of a few hundred noise cells).
float holeThreshold(double probability, int octaves, double persistence, uint32_t seed);

/// The time offset of the first lookup: τ = speed·time along a fixed diagonal.
void holeTimeOffset(double time, double speed, double& ox, double& oy);

/// Whether texel (x, y) is a hole (H = 1 in Eq. 4).
bool isHole(const HoleMap& h, int x, int y);

/// Eq. 4 on the CPU: every non-empty texel that is a hole becomes 1.
std::vector<float> holesReference(const std::vector<float>& depth, int n, const HoleMap& h);

class GpuDevice;

/// The GPU passes on a map uploaded from `depth` and read back (tests; GL thread only).
std::vector<float> epipolarDilationOnGpu(GpuDevice& device, const std::vector<float>& depth, int n, const Epipole& e, int kernelTexels);
std::vector<float> holesOnGpu(GpuDevice& device, const std::vector<float>& depth, int n, const HoleMap& h);

}  // namespace volstyle::core

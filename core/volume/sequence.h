#pragma once
/// \file sequence.h
/// Grids over time (issue #16, the TVCG paper's Sec. "Animation"): carrying a property grid along a
/// velocity field from one frame to another, blending two key frames into the frames between
/// them, and extending a frame's values into its empty voxels by diffusion (the paper's remedy
/// for voxels that are empty in one key frame but not the next). GL-free, on RGB grids (3 floats
/// per voxel, x fastest) of one index space.

#include <cstdint>
#include <vector>

#include "core/math/vec.h"

namespace volstyle::core {

/// A velocity grid in index units per frame (3 per voxel) from one in world units per frame.
std::vector<float> velocityInIndexUnits(const std::vector<float>& worldVelocity, const Mat4& indexFromWorld);

/// `grid` carried `frames` frames along `velocity` (index units per frame): out(x) = grid(x −
/// frames·v(x)), trilinear, clamped to the edge (semi-Lagrangian; `frames` may be negative). No
/// velocity (empty): the grid itself, voxel for voxel.
std::vector<float> advect(const std::vector<float>& grid, Int3 dims, const std::vector<float>& velocity, double frames);

/// (1 − w)·a + w·b.
std::vector<float> blend(const std::vector<float>& a, const std::vector<float>& b, double w);

/// Replaces the values of voxels where `known` is 0 by the harmonic extension of the known ones
/// (Jacobi sweeps of the 6-neighbour Laplacian until nothing moves by more than `tolerance`, at
/// most `maxSweeps`). Known voxels keep their values. Without any known voxel nothing changes.
void extendByDiffusion(std::vector<float>& grid, Int3 dims, const std::vector<uint8_t>& known, int maxSweeps = 500,
                       double tolerance = 1e-5);

}  // namespace volstyle::core

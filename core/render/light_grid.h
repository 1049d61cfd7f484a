#pragma once
/// \file light_grid.h
/// The grid a light-depth volume is stored on: aligned with the light, not with the voxels.
/// Its rows are parallel rays toward the light, one per voxel of spacing across the beam, with a
/// node every voxel along it. light_depth.comp marches each row once, from the light side,
/// writing the optical depth accumulated so far at every node (O(N) for N voxels: every sample is
/// shared by all the nodes below it); the march kernels interpolate it trilinearly between nodes.
/// The per-voxel march it replaced cost O(N^(4/3)) (a ray from every voxel centre). GL-free:
/// the CPU oracle builds the same grid.

#include "core/math/vec.h"

namespace volstyle::core {

struct LightGrid {
    /// Nodes across the beam (x, y) and along it, away from the light (z).
    Int3 dims;
    /// Index-space point → grid coordinates: node (a, b, c) sits at integer (a, b, c); c grows
    /// away from the light. The z column of indexFromGrid is the index-space step between nodes
    /// of a row, of length kLightGridSpacing.
    Mat4 gridFromIndex, indexFromGrid;
};

/// Voxels between neighbouring nodes (across and along the beam).
inline constexpr double kLightGridSpacing = 1.0;

/// The grid of a light shining from world direction `towardLight` onto a volume of `volumeDims`
/// voxels with `indexFromWorld`. Nodes cover the voxels' box [-0.5, n-0.5]³ with a margin of at
/// most one spacing; the lattice is anchored at index 0, so a light along an axis puts nodes on
/// voxel centres.
LightGrid makeLightGrid(Int3 volumeDims, const Mat4& indexFromWorld, const Vec3d& towardLight);

}  // namespace volstyle::core

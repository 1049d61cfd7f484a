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
    /// The light runs along a voxel axis: the nodes sit on voxel centres (and halfway between), so
    /// the depth on a node plane is bilinear between them and is read bilinearly; otherwise the
    /// march kernels read it with a Catmull–Rom spline across the beam (lighting.glsl).
    bool alongAxis = false;
};

/// Voxels between neighbouring nodes (across and along the beam).
inline constexpr double kLightGridSpacing = 1.0;

/// Optical depth one voxel must be able to hold for the rows across the beam to be halved.
/// Interpolating between rows a voxel apart misses the shadow edges of dense media (issue #34:
/// the built-in cloud at 32³ with 0.6 optical depths a voxel, lit from the side: 2.8% relative RMS
/// against the exact light integral with rows a voxel apart, 0.6% at half a voxel). Halving puts
/// 4× the rows in the build (3–4× its time at 64³), so only media denser than this pay it: the
/// built-in cloud at 128³ (0.6) keeps rows a voxel apart and builds no slower than before.
inline constexpr double kDenseVoxelDepth = 1.0;

/// The largest optical depth across one voxel: the largest extinction (per world unit) times the
/// longest voxel edge (world).
double maxVoxelDepth(double maxExtinction, const Mat4& worldFromIndex);

/// Voxels between neighbouring rows across the beam for a medium whose voxels hold up to
/// `voxelDepth`: half a voxel from kDenseVoxelDepth on, else kLightGridSpacing.
double lightGridAcross(double voxelDepth);

/// The grid of a light shining from world direction `towardLight` onto a volume of `volumeDims`
/// voxels with `indexFromWorld`. Nodes cover the voxels' box [-0.5, n-0.5]³ with a margin of at
/// most one spacing; the lattice is anchored at index 0, so a light along an axis puts nodes on
/// voxel centres.
LightGrid makeLightGrid(Int3 volumeDims, const Mat4& indexFromWorld, const Vec3d& towardLight,
                        double across = kLightGridSpacing, double along = kLightGridSpacing);
/// The same over the index-space box [lo, hi] (a sparse volume's active region): nodes cover it,
/// anchored as above, so a box that is the voxels' box gives the grid above.
LightGrid makeLightGrid(const Vec3d& lo, const Vec3d& hi, const Mat4& indexFromWorld, const Vec3d& towardLight,
                        double across = kLightGridSpacing, double along = kLightGridSpacing);

/// The most nodes a sparse volume's light-depth grid may have (512 MiB as r32f): a larger active
/// region spaces its nodes wider, by the cube root of the excess (dense volumes keep their spacing).
inline constexpr double kMaxSparseLightNodes = double(128 << 20);

}  // namespace volstyle::core

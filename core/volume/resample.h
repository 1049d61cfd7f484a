#pragma once
/// \file resample.h
/// Resampling an RGB grid between resolutions of one box (voxel centres at (i + 0.5)/n of it),
/// with the solver's bases: box (nearest voxel) or trilinear (hat functions at voxel centres) —
/// the host-side twin of basisAt() in project.comp. GL-free.

#include <cstddef>
#include <vector>

#include "core/math/vec.h"
#include "core/volume/basis.h"
#include "core/volume/brick_layout.h"

namespace volstyle::core {

/// A grid of RGB values stored with `stride` floats per voxel (3: a Volume grid, 4: a solver
/// vector), x fastest — or through a sparse grid's bricks — starting `offset` floats into `data`.
struct GridView {
    const std::vector<float>& data;
    Int3 dims;
    int stride = 3;
    size_t offset = 0;
    const BrickLayout* bricks = nullptr;  ///< a sparse grid's layout (issue #39): where each voxel is stored; null: dense, x fastest
};

/// The value at index point q (voxel centres at integers; clamped to the grid).
Vec3d sampleGrid(const GridView& grid, const Vec3d& q, BasisType basis);

/// `from` resampled onto dims `to` of the same box, `strideOut` floats per voxel (unused
/// components 0). Equal dims copy exactly.
std::vector<float> resample(const GridView& from, Int3 to, BasisType basis, int strideOut);

}  // namespace volstyle::core

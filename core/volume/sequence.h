#pragma once
/// \file sequence.h
/// Grids over time (issue #16, the TVCG paper's Sec. "Animation"): carrying a property grid along a
/// velocity field from one frame to another, blending two key frames into the frames between
/// them, and extending a frame's values into its empty voxels by diffusion (the paper's remedy
/// for voxels that are empty in one key frame but not the next). GL-free, on RGB grids (3 floats
/// per stored voxel) of one index space: a dense box (x fastest), or a sparse volume's bricks
/// (issue #39), where only the active bricks' voxels are carried and extended.

#include <cstdint>
#include <vector>

#include "core/math/vec.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// Where a grid's voxels are stored: every voxel of a dense box, or the active bricks of a sparse
/// layout (the others read its background slot). Implicit from a box's dims.
class GridSpace {
public:
    GridSpace(Int3 dims) : m_dims(dims) {}  // NOLINT(google-explicit-constructor): a dense box
    explicit GridSpace(const BrickLayout& bricks) : m_dims(bricks.dims()), m_bricks(&bricks) {}
    static GridSpace of(const Volume& v) { return v.bricks() ? GridSpace(*v.bricks()) : GridSpace(v.dims()); }

    Int3 dims() const { return m_dims; }
    size_t storedVoxels() const { return m_bricks ? m_bricks->storedVoxels() : size_t(m_dims.volume()); }
    /// Where voxel v (inside the box) is stored.
    size_t at(Int3 v) const {
        return m_bricks ? m_bricks->storageIndex(v) : (size_t(v.z) * size_t(m_dims.y) + size_t(v.y)) * size_t(m_dims.x) + size_t(v.x);
    }
    /// Whether bricks share a slot (a tile's): advect and extendByDiffusion write voxel by voxel,
    /// so they refuse such a layout.
    bool hasSharedSlots() const { return m_bricks && m_bricks->hasSharedSlots(); }
    /// Whether voxel v (inside the box) has storage of its own (dense: always).
    bool holds(Int3 v) const { return !m_bricks || m_bricks->isActive(m_bricks->brickOf(v)); }
    /// Calls f(Int3 voxel, size_t stored) for every voxel with storage of its own, in storage order.
    template <typename F>
    void forEachVoxel(F&& f) const {
        if (m_bricks) return m_bricks->forEachStoredVoxel(f);
        size_t n = 0;
        for (int k = 0; k < m_dims.z; ++k)
            for (int j = 0; j < m_dims.y; ++j)
                for (int i = 0; i < m_dims.x; ++i, ++n) f(Int3{i, j, k}, n);
    }

private:
    Int3 m_dims;
    const BrickLayout* m_bricks = nullptr;
};

/// A velocity grid in index units per frame (3 per voxel) from one in world units per frame.
std::vector<float> velocityInIndexUnits(const std::vector<float>& worldVelocity, const Mat4& indexFromWorld);

/// `grid` carried `frames` frames along `velocity` (index units per frame): out(x) = grid(x −
/// frames·v(x)), trilinear, clamped to the edge (semi-Lagrangian; `frames` may be negative). No
/// velocity (empty): the grid itself, voxel for voxel. Sparse: each voxel of the active bricks
/// is carried (a corner in an inactive brick reads the background); the background stays.
std::vector<float> advect(const std::vector<float>& grid, const GridSpace& space, const std::vector<float>& velocity, double frames);

/// (1 − w)·a + w·b.
std::vector<float> blend(const std::vector<float>& a, const std::vector<float>& b, double w);

/// Replaces the values of voxels where `known` is 0 by the harmonic extension of the known ones
/// (Jacobi sweeps of the 6-neighbour Laplacian until nothing moves by more than `tolerance`, at
/// most `maxSweeps`). Known voxels keep their values. Without any known voxel nothing changes.
/// `known` has one entry per stored voxel. Sparse: only the active bricks' voxels are extended,
/// and the active region's border is zero-flux, like the box's.
void extendByDiffusion(std::vector<float>& grid, const GridSpace& space, const std::vector<uint8_t>& known, int maxSweeps = 500,
                       double tolerance = 1e-5);

}  // namespace volstyle::core

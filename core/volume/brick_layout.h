#pragma once
/// \file brick_layout.h
/// The storage of a sparse volume (issue #39): the box is cut into bricks of kBrickSide³ voxels,
/// and only the active ones are stored. A grid of a sparse volume holds one brick after another in
/// slot order (3 floats a voxel, x fastest inside the brick, then y, then z); slot 0 is the
/// background brick, which every inactive brick reads (extinction and emission 0, albedo its
/// default): an absent brick costs nothing and needs no branch to read. The GPU keeps the same
/// slots in an atlas with a table from brick to slot (gpu_volume.h), so an upload is one copy.
///
/// Bricks line up with the file's OpenVDB leaf nodes (8³ at multiples of 8 in file index space):
/// the volume's voxel (i,j,k) lies in brick ((i,j,k) + offset) / kBrickSide, with `offset` the
/// position of voxel 0 inside its brick. A leaf is then one brick, read without densifying.
///
/// Tiles stay tiles: the bricks inside an OpenVDB tile (a constant region of 128³ or more) hold one
/// value, so every such brick with the same values reads one shared slot. A shared slot is
/// read-only; activate() gives a brick a slot of its own (Volume::activateBrick copies the values).

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/math/vec.h"

namespace volstyle::core {

/// The brick edge, in voxels: the GPU's kBrickSize (core/shaders/layout.h; gpu_volume.cpp checks
/// they agree), so the occupancy bricks are these bricks.
inline constexpr int kBrickSide = 8;
inline constexpr int kBrickVoxels = kBrickSide * kBrickSide * kBrickSide;

class BrickLayout {
public:
    BrickLayout() = default;
    /// No brick active yet: every brick reads the background slot.
    BrickLayout(Int3 dims, Int3 offset);
    /// Every brick of the box active, in x-fastest order (a dense volume as bricks).
    static BrickLayout full(Int3 dims, Int3 offset = {0, 0, 0});

    Int3 dims() const { return m_dims; }
    Int3 offset() const { return m_offset; }
    Int3 brickDims() const { return m_brickDims; }
    /// Stored bricks, the background slot 0 included.
    size_t slots() const { return m_brickOfSlot.size(); }
    /// Bricks that hold data (their own slot or a shared one).
    size_t activeBricks() const { return m_activeBricks; }
    /// Whether a slot is shared by the bricks of a tile (its brickOfSlot is one of them).
    bool isShared(size_t slot) const { return m_shared[slot] != 0; }
    /// Whether any brick reads a shared slot.
    bool hasSharedSlots() const { return m_sharingBricks > 0; }
    /// Voxels stored, the background brick included (what the grids hold).
    size_t storedVoxels() const { return slots() * size_t(kBrickVoxels); }

    size_t brickIndex(Int3 b) const { return (size_t(b.z) * size_t(m_brickDims.y) + size_t(b.y)) * size_t(m_brickDims.x) + size_t(b.x); }
    /// The brick holding voxel v (v inside the box).
    Int3 brickOf(Int3 v) const {
        return {(v.x + m_offset.x) / kBrickSide, (v.y + m_offset.y) / kBrickSide, (v.z + m_offset.z) / kBrickSide};
    }
    /// The first voxel of brick b (may be negative: the low bricks start before the box).
    Int3 firstVoxel(Int3 b) const {
        return {b.x * kBrickSide - m_offset.x, b.y * kBrickSide - m_offset.y, b.z * kBrickSide - m_offset.z};
    }
    uint32_t slotOf(Int3 b) const { return m_slotOfBrick[brickIndex(b)]; }
    Int3 brickOfSlot(size_t slot) const { return m_brickOfSlot[slot]; }
    /// Where voxel v is stored (in voxels; × 3 for a grid's floats): in the background slot when
    /// its brick is inactive.
    size_t storageIndex(Int3 v) const {
        const Int3 b = brickOf(v);
        const int lx = (v.x + m_offset.x) % kBrickSide, ly = (v.y + m_offset.y) % kBrickSide, lz = (v.z + m_offset.z) % kBrickSide;
        return size_t(slotOf(b)) * kBrickVoxels + size_t((lz * kBrickSide + ly) * kBrickSide + lx);
    }
    bool isActive(Int3 b) const { return slotOf(b) != 0; }
    /// Gives brick b a slot of its own (no-op when it has one): a new slot when it was inactive or
    /// read a shared one. Returns its slot. Grids grow with Volume::activateBrick.
    uint32_t activate(Int3 b);
    /// A new shared slot, standing for `representative` (a brick of the tile; no slot of its own yet).
    uint32_t addSharedSlot(Int3 representative);
    /// Inactive brick b reads shared slot `slot`.
    void share(Int3 b, uint32_t slot);
    /// Calls f(Int3 brick, uint32_t slot) for every active brick, x fastest.
    template <typename F>
    void forEachActiveBrick(F&& f) const {
        size_t i = 0;
        for (int z = 0; z < m_brickDims.z; ++z)
            for (int y = 0; y < m_brickDims.y; ++y)
                for (int x = 0; x < m_brickDims.x; ++x, ++i)
                    if (m_slotOfBrick[i] != 0) f(Int3{x, y, z}, m_slotOfBrick[i]);
    }
    /// Calls f(Int3 brick) for every brick of the box within `radius` bricks of b along each axis
    /// (b itself included), x fastest.
    template <typename F>
    void forEachBrickAround(Int3 b, int radius, F&& f) const {
        for (int z = std::max(b.z - radius, 0); z <= std::min(b.z + radius, m_brickDims.z - 1); ++z)
            for (int y = std::max(b.y - radius, 0); y <= std::min(b.y + radius, m_brickDims.y - 1); ++y)
                for (int x = std::max(b.x - radius, 0); x <= std::min(b.x + radius, m_brickDims.x - 1); ++x) f(Int3{x, y, z});
    }
    /// The table from brick to slot (x fastest), as the GPU's indirection texture holds it.
    const std::vector<uint32_t>& slotTable() const { return m_slotOfBrick; }

    /// Calls f(Int3 voxel, size_t stored) for every voxel of the active bricks inside the box
    /// (the bricks of a tile all give their shared slot's stored voxels).
    template <typename F>
    void forEachStoredVoxel(F&& f) const {
        forEachActiveBrick([&](Int3 brick, uint32_t slot) {
            const Int3 first = firstVoxel(brick);
            size_t stored = slot * size_t(kBrickVoxels);
            for (int z = 0; z < kBrickSide; ++z)
                for (int y = 0; y < kBrickSide; ++y)
                    for (int x = 0; x < kBrickSide; ++x, ++stored) {
                        const Int3 p{first.x + x, first.y + y, first.z + z};
                        if (p.x >= 0 && p.y >= 0 && p.z >= 0 && p.x < m_dims.x && p.y < m_dims.y && p.z < m_dims.z) f(p, stored);
                    }
        });
    }

    /// The inclusive voxel box covered by active bricks, clipped to the volume (lo > hi: none).
    std::pair<Int3, Int3> activeVoxelBox() const;

    /// Bytes of the table and bookkeeping (not the grids).
    size_t tableBytes() const { return m_slotOfBrick.size() * sizeof(uint32_t) + m_brickOfSlot.size() * (sizeof(Int3) + 1); }

    bool operator==(const BrickLayout& o) const {
        return m_dims == o.m_dims && m_offset == o.m_offset && m_slotOfBrick == o.m_slotOfBrick;
    }

private:
    Int3 m_dims, m_offset, m_brickDims;
    std::vector<uint32_t> m_slotOfBrick;  ///< per brick of the box: its slot, 0 when inactive
    std::vector<Int3> m_brickOfSlot;      ///< per slot: its brick (slot 0: unused; shared: one of them)
    std::vector<uint8_t> m_shared;        ///< per slot: 1 when shared by a tile's bricks
    size_t m_activeBricks = 0, m_sharingBricks = 0;  ///< bricks with data; those of them reading a shared slot
};

}  // namespace volstyle::core

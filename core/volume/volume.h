#pragma once
/// \file volume.h
/// A host-side participating-medium volume (SPEC §1): RGB extinction, albedo and emission grids on
/// one index space, and the index-to-world transform (voxel (i,j,k) has its centre at
/// worldFromIndex·(i,j,k)). Values are trilinear between voxel centres, clamped to the edge inside
/// the voxels' box [-0.5, n-0.5]³ (index space), and zero outside it.
///
/// Dense volumes store every voxel of the box (x fastest). Sparse ones (issue #39) store only their
/// active bricks (brick_layout.h): the grids then hold bricks in slot order, the background brick
/// first, and index() maps a voxel to its place there. Code that walks a grid as a dense box asks
/// isSparse() first (or requireDense()).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/volume/brick_layout.h"

namespace volstyle::core {

/// How a loaded volume is stored: dense when its box fits VolumeLimits::maxVoxels (exactly as
/// before sparse volumes existed), else sparse; or one of them always.
enum class VolumeStorage { Automatic, Dense, Sparse };
/// "auto", "dense", "sparse"; volumeStorageNamed throws InvalidArgument for any other name.
const char* volumeStorageName(VolumeStorage storage);
VolumeStorage volumeStorageNamed(const std::string& name);

/// What a volume may be; over these, loading fails with a message naming the limit, before the
/// grids are allocated.
struct VolumeLimits {
    /// Dense volumes: voxels of the box, and voxels on a side.
    int64_t maxVoxels = int64_t(256) * 256 * 256;
    int maxSide = 1024;
    /// Sparse volumes: voxels of the active bricks, the bytes their grids take, and the box's side.
    int64_t maxActiveVoxels = int64_t(256) << 20;
    int64_t maxSparseBytes = int64_t(8) << 30;
    int maxSparseSide = 4096;  // a brick table of at most 512³ entries (512 MiB)
    VolumeStorage storage = VolumeStorage::Automatic;
};

/// What a volume read from a VDB file keeps of that file, so that writing it again loses nothing:
/// the file's grids as read (names, value types, classes, transforms, metadata, the grids volstyle
/// does not use), its metadata and the index box the volume covers. Defined in vdb_file.h, which
/// only the OpenVDB translation units include; immutable and shared by every copy of the volume.
struct VdbSource;

/// Defaults for absent grids: albedo 1 (white, lossless scattering: a cloud), emission 0.
constexpr float kDefaultAlbedo = 1.0f;

class Volume {
public:
    Volume() = default;
    /// A volume of `dims` voxels, all extinction zero, with no albedo or emission grid.
    Volume(Int3 dims, const Mat4& worldFromIndex);
    /// A sparse volume stored as `bricks`, all extinction zero, with no albedo or emission grid.
    Volume(BrickLayout bricks, const Mat4& worldFromIndex);

    bool isSparse() const { return m_bricks.has_value(); }
    /// The bricks of a sparse volume, else null.
    const BrickLayout* bricks() const { return m_bricks ? &*m_bricks : nullptr; }
    /// Voxels each grid stores: the box's for a dense volume, the active bricks' (and the
    /// background brick's) for a sparse one.
    size_t storedVoxels() const { return m_bricks ? m_bricks->storedVoxels() : voxelCount(); }
    /// Voxels that hold data: the box's, or the active bricks' (clipped to the box, background excluded).
    size_t activeVoxels() const;
    /// Gives brick b of a sparse volume a slot of its own, holding what it read before (the
    /// background's values, or its tile's). Returns its slot.
    uint32_t activateBrick(Int3 b);
    /// Gives every brick of a tile a slot of its own (before writing voxel by voxel: a solve).
    void unshareTiles();
    /// Activates every brick within `radius` bricks (along each axis) of an active one: where an
    /// edit that moves or spreads the medium by up to 8·radius voxels can write.
    void activateBricksAround(int radius);
    /// The voxel of the box a stored voxel belongs to (the inverse of index(); background: none).
    Int3 voxelOfStored(size_t stored) const;
    /// The same volume stored densely (throws LimitExceeded over `limits`).
    Volume toDense(const VolumeLimits& limits = {}) const;
    /// The same volume stored as bricks with `offset` (every brick holding a voxel that differs
    /// from the background active).
    Volume toSparse(Int3 offset = {0, 0, 0}) const;
    /// The same volume stored in `bricks` (of the same box): each voxel of its active bricks holds
    /// this volume's value there; the background slot keeps this volume's background (a dense
    /// volume's: the grids' defaults). Voxels outside `bricks` are dropped.
    Volume onBricks(const BrickLayout& bricks) const;

    Int3 dims() const { return m_dims; }
    size_t voxelCount() const { return size_t(m_dims.volume()); }
    const Mat4& worldFromIndex() const { return m_worldFromIndex; }
    void setWorldFromIndex(const Mat4& m) { m_worldFromIndex = m; }

    /// RGB, 3 floats per stored voxel (dense: x fastest then y then z). Albedo and emission may be empty
    /// (absent: kDefaultAlbedo and 0).
    std::vector<float>& extinction() { return m_extinction; }
    const std::vector<float>& extinction() const { return m_extinction; }
    std::vector<float>& albedo() { return m_albedo; }
    const std::vector<float>& albedo() const { return m_albedo; }
    std::vector<float>& emission() { return m_emission; }
    const std::vector<float>& emission() const { return m_emission; }
    std::optional<std::vector<float>>& refractiveIndex() { return m_refractiveIndex; }
    const std::optional<std::vector<float>>& refractiveIndex() const { return m_refractiveIndex; }

    /// The file this volume was read from, or null (built-in scenes, volumes made in memory).
    /// Copies (solve results, versions) share it: saveVdb writes what they changed into it.
    const std::shared_ptr<const VdbSource>& vdbSource() const { return m_vdbSource; }
    void setVdbSource(std::shared_ptr<const VdbSource> source) { m_vdbSource = std::move(source); }

    /// Bytes its grids (and brick table) take in memory.
    size_t memoryBytes() const {
        return (m_extinction.size() + m_albedo.size() + m_emission.size() + (m_refractiveIndex ? m_refractiveIndex->size() : 0)) *
                   sizeof(float) +
               (m_bricks ? m_bricks->tableBytes() : 0);
    }

    bool hasAlbedo() const { return !m_albedo.empty(); }
    bool hasEmission() const { return !m_emission.empty(); }
    /// Allocates the albedo (filled with `value`) or emission (0) grid if absent.
    std::vector<float>& ensureAlbedo(float value = kDefaultAlbedo);
    std::vector<float>& ensureEmission();

    /// Where voxel (i,j,k) is stored (× 3 for an RGB grid). Sparse: in the background brick when
    /// its brick is inactive (read it; activateBrick before writing).
    size_t index(int i, int j, int k) const {
        if (m_bricks) return m_bricks->storageIndex({i, j, k});
        return (size_t(k) * m_dims.y + size_t(j)) * m_dims.x + size_t(i);
    }
    void setExtinction(int i, int j, int k, Vec3 v) { put(m_extinction, i, j, k, v); }
    Vec3 extinctionAt(int i, int j, int k) const { return get(m_extinction, i, j, k); }

    /// World-space axis-aligned bounds of the voxels' box (the corners of [-0.5, n-0.5]³).
    std::pair<Vec3d, Vec3d> worldBounds() const;
    /// World length of one voxel step along each index axis.
    Vec3d voxelSize() const;

    /// Throws InvalidArgument: grid sizes disagree with dims, non-finite or negative values
    /// (albedo outside [0,1]), dims over `limits`, a singular transform.
    void validate(const VolumeLimits& limits = {}) const;

    /// Smallest and largest value of each channel of a grid (for `volstyle info`).
    static std::pair<Vec3, Vec3> range(const std::vector<float>& rgb);
    /// Whether every voxel of an RGB grid has r = g = b (written as float; light depth in one channel).
    static bool isGrey(const std::vector<float>& rgb);

private:
    static void put(std::vector<float>& g, size_t idx, Vec3 v) {
        g[3 * idx] = v.x, g[3 * idx + 1] = v.y, g[3 * idx + 2] = v.z;
    }
    void put(std::vector<float>& g, int i, int j, int k, Vec3 v) { put(g, index(i, j, k), v); }
    Vec3 get(const std::vector<float>& g, int i, int j, int k) const {
        size_t idx = index(i, j, k);
        return {g[3 * idx], g[3 * idx + 1], g[3 * idx + 2]};
    }

    Int3 m_dims;
    Mat4 m_worldFromIndex;
    std::optional<BrickLayout> m_bricks;
    std::vector<float> m_extinction, m_albedo, m_emission;
    std::optional<std::vector<float>> m_refractiveIndex;
    std::shared_ptr<const VdbSource> m_vdbSource;
};

/// Calls f(Int3 voxel, size_t stored) for every voxel of the box that holds data: each voxel of a
/// dense volume; each voxel of a sparse one's active bricks that lies inside the box (the bricks
/// of a tile all give their shared slot's stored voxels).
template <typename F>
void forEachActiveVoxel(const Volume& v, F&& f) {
    if (const BrickLayout* bricks = v.bricks()) return bricks->forEachStoredVoxel(f);
    const Int3 d = v.dims();
    size_t n = 0;
    for (int k = 0; k < d.z; ++k)
        for (int j = 0; j < d.y; ++j)
            for (int i = 0; i < d.x; ++i, ++n) f(Int3{i, j, k}, n);
}

/// Throws LimitExceeded when a sparse volume of `dims` with `activeBricks` (stored in `storedSlots`
/// slots, tiles sharing theirs) and `rgbGrids` grids is over `limits` (checked before its grids
/// are allocated, and by validate()).
void checkSparseLimits(Int3 dims, size_t activeBricks, size_t storedSlots, int rgbGrids, const VolumeLimits& limits);

/// `grid` (`channels` floats per stored voxel of `from`) stored in `bricks` (of from's box), as
/// Volume::onBricks does it; `background` fills the background slot when `from` is dense.
std::vector<float> gridOnBricks(const Volume& from, const std::vector<float>& grid, int channels, const BrickLayout& bricks,
                                float background);

/// Throws InvalidArgument naming `what` when `volume` is sparse (code that walks the dense box).
void requireDense(const Volume& volume, const char* what);

/// Voxels of a grid with a value outside [lo, hi] or not finite: how many, and the first (flat
/// voxel index) with its bad value.
struct InvalidValues {
    size_t count = 0;  ///< voxels
    size_t firstVoxel = 0;
    float firstValue = 0;
};
/// `channels` floats per voxel (3 for RGB grids, 1 for refractive index).
InvalidValues findInvalidValues(const std::vector<float>& grid, int channels, float lo, float hi);

}  // namespace volstyle::core

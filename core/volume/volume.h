#pragma once
/// \file volume.h
/// A dense, host-side participating-medium volume (SPEC §1): RGB extinction, albedo and emission
/// grids on one index space, and the index-to-world transform (voxel (i,j,k) has its centre at
/// worldFromIndex·(i,j,k)). Values are trilinear between voxel centres, clamped to the edge inside
/// the voxels' box [-0.5, n-0.5]³ (index space), and zero outside it.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/math/vec.h"

namespace volstyle::core {

/// What a volume may be; over these, loading fails with a message naming the limit.
struct VolumeLimits {
    int64_t maxVoxels = int64_t(256) * 256 * 256;
    int maxSide = 1024;
};

/// What a volume read from a VDB file keeps of that file, so that writing it again loses nothing:
/// the file's grids as read (names, value types, classes, transforms, metadata, the grids volstyle
/// does not use), its metadata and the index box the dense grids cover. Opaque outside vdb_io.cpp,
/// the one translation unit that includes OpenVDB; immutable and shared by every copy of the volume.
struct VdbSource;

/// Defaults for absent grids: albedo 1 (white, lossless scattering: a cloud), emission 0.
constexpr float kDefaultAlbedo = 1.0f;

class Volume {
public:
    Volume() = default;
    /// A volume of `dims` voxels, all extinction zero, with no albedo or emission grid.
    Volume(Int3 dims, const Mat4& worldFromIndex);

    Int3 dims() const { return m_dims; }
    size_t voxelCount() const { return size_t(m_dims.volume()); }
    const Mat4& worldFromIndex() const { return m_worldFromIndex; }
    void setWorldFromIndex(const Mat4& m) { m_worldFromIndex = m; }

    /// RGB, 3 floats per voxel, x fastest then y then z. Albedo and emission may be empty
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

    /// Bytes its grids take in memory.
    size_t memoryBytes() const {
        return (m_extinction.size() + m_albedo.size() + m_emission.size() + (m_refractiveIndex ? m_refractiveIndex->size() : 0)) *
               sizeof(float);
    }

    bool hasAlbedo() const { return !m_albedo.empty(); }
    bool hasEmission() const { return !m_emission.empty(); }
    /// Allocates the albedo (filled with `value`) or emission (0) grid if absent.
    std::vector<float>& ensureAlbedo(float value = kDefaultAlbedo);
    std::vector<float>& ensureEmission();

    size_t index(int i, int j, int k) const {
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
    std::vector<float> m_extinction, m_albedo, m_emission;
    std::optional<std::vector<float>> m_refractiveIndex;
    std::shared_ptr<const VdbSource> m_vdbSource;
};

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

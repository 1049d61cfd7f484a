#pragma once
/// \file gpu_volume.h
/// A Volume resident on the GPU: RGB32F 3D textures for extinction, albedo and emission (absent
/// grids are not uploaded), and the occupancy bricks used for empty-space skipping. GL thread only.
/// A sparse volume's grids are atlases of its stored bricks, in slot order, with a table from brick
/// to atlas brick (common/volume.glsl reads through it; kernels compile with VOLSTYLE_SPARSE).
/// GL-free header: texture names are plain unsigned integers (GLuint) for the kernels' C++ sides.

#include <cstdint>
#include <memory>

#include "core/math/vec.h"
#include "core/volume/volume.h"

namespace volstyle::core {

class RefractiveGrid;  // core/render/curved_paths.h

class GpuVolume {
public:
    /// Uploads `volume` (validated first; throws InvalidArgument, GpuError if too large for GL).
    explicit GpuVolume(const Volume& volume);
    ~GpuVolume();
    GpuVolume(const GpuVolume&) = delete;
    GpuVolume& operator=(const GpuVolume&) = delete;

    /// Re-uploads from `volume` (same or different dimensions). Bumps the extinction version
    /// only if the extinction grid changed, so light volumes and occupancy are kept otherwise.
    void upload(const Volume& volume);

    Int3 dims() const { return m_dims; }
    Int3 brickDims() const { return m_brickDims; }
    const Mat4& worldFromIndex() const { return m_worldFromIndex; }
    bool hasAlbedo() const;
    bool hasEmission() const;
    /// Whether every extinction voxel has r = g = b (light depth then needs one channel).
    bool extinctionIsGrey() const { return m_extinctionIsGrey; }
    /// Largest emission value (any channel), for bounding what a ray can still gather.
    float maxEmission() const { return m_maxEmission; }
    /// Largest extinction value (any channel, per world unit).
    float maxExtinction() const { return m_maxExtinction; }
    unsigned extinctionTexture() const;
    unsigned albedoTexture() const;
    unsigned emissionTexture() const;
    unsigned occupancyTexture() const;
    /// Sparse volumes: the r32ui table from brick to atlas brick (else 0), and where voxel 0 lies in its brick.
    bool isSparse() const { return m_sparse; }
    unsigned brickTableTexture() const;
    Int3 sparseOffset() const { return m_sparseOffset; }
    /// The index box holding everything a sample can read as non-zero extinction, inclusive:
    /// the box, or a sparse volume's active bricks with a voxel of margin (clipped to the box).
    std::pair<Int3, Int3> activeBox() const { return m_activeBox; }
    /// Voxels each grid stores (a sparse volume's slots × 8³, the background brick included).
    size_t storedVoxels() const { return m_storedVoxels; }
    /// Bytes the textures take (grids, table, occupancy).
    size_t deviceBytes() const { return m_deviceBytes; }

    /// A number unique to this volume's current extinction (across all GpuVolumes): caches of
    /// derived data (occupancy, light depth) compare it to know when to recompute.
    uint64_t extinctionVersion() const { return m_extinctionVersion; }
    uint64_t occupancyVersion() const { return m_occupancyVersion; }
    /// A hash of the extinction's content: equal for equal grids in different GpuVolumes (each
    /// solve's copy), so derived data that is costly to rebuild can be shared between them.
    size_t extinctionHash() const { return m_extinctionHash; }
    void markOccupancyCurrent() { m_occupancyVersion = m_extinctionVersion; }
    /// The refractive-index grid when it bends rays (curved_paths.h), else null.
    const std::shared_ptr<const RefractiveGrid>& refraction() const { return m_refraction; }

private:
    struct Textures;
    std::unique_ptr<Textures> m_textures;
    Int3 m_dims, m_brickDims, m_sparseOffset;
    size_t m_storedVoxels = 0;
    std::pair<Int3, Int3> m_activeBox;
    bool m_sparse = false;
    size_t m_tableHash = 0;  // to detect an unchanged brick layout on re-upload
    size_t m_deviceBytes = 0;
    Mat4 m_worldFromIndex;
    std::shared_ptr<const RefractiveGrid> m_refraction;
    size_t m_extinctionHash = 0;  // to detect unchanged extinction on re-upload
    float m_maxEmission = 0;
    float m_maxExtinction = 0;
    bool m_extinctionIsGrey = true;
    uint64_t m_extinctionVersion = 0;
    uint64_t m_occupancyVersion = 0;
};

}  // namespace volstyle::core

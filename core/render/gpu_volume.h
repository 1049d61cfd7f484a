#pragma once
/// \file gpu_volume.h
/// A Volume resident on the GPU: RGB32F 3D textures for extinction, albedo and emission (absent
/// grids are not uploaded), and the occupancy bricks used for empty-space skipping. GL thread only.

#include <cstdint>

#include "core/gl/object.h"
#include "core/math/vec.h"
#include "core/volume/volume.h"

namespace volstyle::core {

class GpuVolume {
public:
    /// Uploads `volume` (validated first; throws InvalidArgument, GpuError if too large for GL).
    explicit GpuVolume(const Volume& volume);

    /// Re-uploads from `volume` (same or different dimensions). Bumps the extinction version
    /// only if the extinction grid changed, so light volumes and occupancy are kept otherwise.
    void upload(const Volume& volume);

    Int3 dims() const { return m_dims; }
    Int3 brickDims() const { return m_brickDims; }
    const Mat4& worldFromIndex() const { return m_worldFromIndex; }
    bool hasAlbedo() const { return bool(m_albedo); }
    bool hasEmission() const { return bool(m_emission); }
    /// Largest emission value (any channel), for bounding what a ray can still gather.
    float maxEmission() const { return m_maxEmission; }
    GLuint extinctionTexture() const { return m_extinction.id(); }
    GLuint albedoTexture() const { return m_albedo.id(); }
    GLuint emissionTexture() const { return m_emission.id(); }
    GLuint occupancyTexture() const { return m_occupancy.id(); }

    /// A number unique to this volume's current extinction (across all GpuVolumes): caches of
    /// derived data (occupancy, light depth) compare it to know when to recompute.
    uint64_t extinctionVersion() const { return m_extinctionVersion; }
    uint64_t occupancyVersion() const { return m_occupancyVersion; }
    void markOccupancyCurrent() { m_occupancyVersion = m_extinctionVersion; }

private:
    Int3 m_dims, m_brickDims;
    Mat4 m_worldFromIndex;
    gl::Texture m_extinction, m_albedo, m_emission, m_occupancy;
    size_t m_extinctionHash = 0;
    float m_maxEmission = 0;  // to detect unchanged extinction on re-upload
    uint64_t m_extinctionVersion = 0;
    uint64_t m_occupancyVersion = 0;
};

}  // namespace volstyle::core

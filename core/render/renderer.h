#pragma once
/// \file renderer.h
/// The single-scattering renderer on GL compute (SPEC §1). Keeps compiled shader variants, brick
/// occupancy and light-depth volumes between frames, recomputing each only when the extinction or
/// the light it depends on changes. GL thread only.

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/gl/context.h"
#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/image/image.h"
#include "core/render/gpu_volume.h"
#include "core/render/params.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

/// What one render did, for benchmarks and logs.
struct RenderStats {
    double gpuMs = 0;          ///< the render dispatch (GPU timer query)
    double lightMs = 0;        ///< light-depth volumes recomputed this frame (0 when cached)
    double occupancyMs = 0;    ///< occupancy recomputed this frame (0 when cached)
    double totalMs = 0;        ///< wall clock including readback
    int lightVolumesRecomputed = 0;
};

class Renderer {
public:
    explicit Renderer(gl::Context& context);
    ~Renderer();

    /// Renders linear RGBA (alpha = 1 − mean transmittance). Throws InvalidArgument for an
    /// invalid camera, lighting or settings.
    Image render(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                 const RenderSettings& settings = {}, RenderStats* stats = nullptr);

    /// Drops cached light volumes and occupancy-derived data (e.g. before freeing a volume).
    void clearCaches();

    /// What every march kernel (this renderer's, the solver's projector) shares: the uniform
    /// block for `camera`, and the light-depth volumes of the lights with non-zero irradiance.
    struct MarchSetup {
        layout::MarchParams params;
        std::vector<GLuint> lightTextures;
    };
    /// Updates occupancy and light volumes if stale and fills the uniform block.
    MarchSetup prepareMarch(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                            const RenderSettings& settings, RenderStats& stats);
    /// Uploads the block and binds extinction, occupancy, environment and light-depth textures.
    void bindMarch(const GpuVolume& volume, const Lighting& lighting, const MarchSetup& setup);
    /// The compiled program of a variant (compiled once, then cached).
    const gl::Program& program(const gl::ShaderBuilder& builder);
    gl::Context& context() { return m_context; }

private:
    struct LightVolume;
    void updateOccupancy(GpuVolume& volume, RenderStats& stats);
    GLuint lightDepthTexture(GpuVolume& volume, const DirectionalLight& light, const RenderSettings& march,
                             RenderStats& stats);
    void uploadParams(const void* data, size_t bytes);
    GLuint environmentTexture(const std::shared_ptr<const Image>& env);
    /// An upper bound on the radiance a ray can gather per unit opacity (early termination).
    double radianceBound(const GpuVolume& volume, const Lighting& lighting);

    gl::Context& m_context;
    std::map<std::string, gl::Program> m_programs;
    std::vector<std::unique_ptr<LightVolume>> m_lightVolumes;
    gl::Buffer m_params;
    gl::Buffer m_pixels;
    size_t m_pixelBytes = 0;
    gl::Texture m_environment;
    std::shared_ptr<const Image> m_environmentSource;  // held so its address is never reused
    gl::GpuTimer m_timer;
    uint64_t m_frame = 0;
    std::shared_ptr<const Image> m_boundSource;  // environment whose maximum is cached
    double m_environmentMax = 0;
};

}  // namespace volstyle::core

#pragma once
/// \file lights_projector.h
/// The `lights` unknown's operator (SPEC §8; TVCG Sec. 4.4, 5.3): with the volume fixed, a pixel
/// is linear in the radiances c of the environment's lobes, o = T c. T's columns are renderings
/// of the volume under one lobe each; they are never stored: T c marches every view ray once and
/// gathers all lobes' light volumes (lights_project.comp), Tᵀ r marches them once per
/// kLobeChunk lobes and reduces the rays' sums per workgroup in shared memory (no atomics), the
/// host adding the groups' sums in double. Unknowns are per lobe and RGB channel, so they live on
/// the host. GL thread only.

#include <memory>
#include <vector>

#include "core/base/work_budget.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/render/march_setup.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/solve/gpu_vector.h"

namespace volstyle::core {

class LightsProjector {
public:
    /// The lobes of `lighting.environment` (its basis, domain and light-volume resolution; its
    /// radiances are the unknowns and are ignored) and the phase function; lights are not part of
    /// T, nor is the background, unless it is the lobes (Background::fromLobes): then each ray's
    /// transmittance T(0,s) joins the column of the lobe whose cell its direction falls in.
    LightsProjector(GpuDevice& device, GpuVolume& volume, const Lighting& lighting, double stepVoxels);
    ~LightsProjector();

    /// Builds the light volumes on first use (cached), checking `budget` between lobes. A view with
    /// a plate (SolveView::background) sees the plate, not the lobes, behind the volume.
    void addView(const Camera& camera, const WorkBudget& budget = WorkBudget(), std::shared_ptr<const Image> plate = nullptr);
    size_t pixelCount() const { return m_pixelCount; }
    int lobes() const { return m_lobes; }

    /// T c: `radiance` (one per lobe) → every view's pixels (rgb), in addView order.
    void forward(const std::vector<Vec3d>& radiance, GpuVector& pixels);
    /// Tᵀ r: per-pixel residuals → one RGB value per lobe.
    std::vector<Vec3d> adjoint(const GpuVector& residual);

    double lightVolumeMs() const { return m_lightVolumeMs; }
    size_t lightVolumeBytes() const;

private:
    struct View {
        Camera camera;
        MarchSetup setup;
        size_t firstPixel;
    };
    void use(const View& view, bool adjoint);

    GpuDevice& m_device;
    GpuVolume& m_volume;
    Lighting m_lighting;
    double m_step;
    int m_lobes = 0;
    size_t m_pixelCount = 0;
    double m_lightVolumeMs = 0;
    std::vector<View> m_views;
    struct Sums;
    std::unique_ptr<Sums> m_sums;
};

}  // namespace volstyle::core

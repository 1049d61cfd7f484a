#pragma once
/// \file reference_projector.h
/// Float64 oracle of project.comp: W a and Wᵀ r with plain loops, the same segments, weights and
/// basis. Vectors are 4 doubles per element (rgb used) like the GPU's. For tiny problems only.

#include <memory>
#include <vector>

#include "core/cpu_ref/reference_renderer.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_types.h"
#include "core/volume/volume.h"

namespace volstyle::core::cpu_ref {

namespace detail {
struct BrickBound;
}

struct ProjectionSpec {
    Unknown unknown = Unknown::Emission;
    BasisType basis = BasisType::Trilinear;
    Int3 unknownDims;
    double stepVoxels = 0.5;
};

class ReferenceProjector {
public:
    ReferenceProjector(const Volume& volume, const Lighting& lighting, const std::vector<Camera>& cameras,
                       const ProjectionSpec& spec);
    size_t pixelCount() const { return m_pixelCount; }
    size_t elementCount() const;
    std::vector<double> forward(const std::vector<double>& a) const;
    std::vector<double> adjoint(const std::vector<double>& r) const;

private:
    /// Calls visit(element, weight RGB) for every basis function a pixel's ray touches.
    template <typename Visit>
    void march(size_t view, int px, int py, Visit&& visit) const;

    const Volume& m_volume;
    Lighting m_lighting;
    std::vector<Camera> m_cameras;
    ProjectionSpec m_spec;
    std::vector<LightDepthGrid<double>> m_lightDepth;
    std::shared_ptr<const detail::BrickBound> m_bricks;  // march.glsl's dense segments
    size_t m_pixelCount = 0;
};

}  // namespace volstyle::core::cpu_ref

#pragma once
/// \file reference_renderer.h
/// A straightforward CPU oracle of the GL renderer (STYLE §3.7): the same image formation, the same
/// segment quadrature and the same light-depth volume, in templated precision (double in tests),
/// with plain loops and no skipping or early termination. Slow: for tiny volumes and images.

#include "core/image/image.h"
#include "core/render/light_grid.h"
#include "core/render/params.h"
#include "core/volume/volume.h"

namespace volstyle::core::cpu_ref {

/// How the oracle gets the optical depth toward a light at a sample point p.
enum class LightDepthMethod {
    Grid,          ///< as the GL path: light_depth.comp's light-aligned grid, trilinear between nodes
    Exact,         ///< a march from p itself to the box (the quantity the grids approximate)
    VoxelCentres,  ///< a march from every voxel centre, trilinear between them (before issue #10)
};

template <typename Scalar>
Image renderReference(const Volume& volume, const Camera& camera, const Lighting& lighting,
                      double stepVoxels, LightDepthMethod method = LightDepthMethod::Grid);

/// Optical depth toward `lightDirection` (world, toward the light) from index-space point p,
/// marched in equal segments of at most `stepVoxels` to the voxels' box.
template <typename Scalar>
Vec3T<Scalar> opticalDepthToLight(const Volume& volume, const Vec3T<Scalar>& p, const Vec3d& lightDirection,
                                  double stepVoxels);

/// The light-depth volume of light_depth.comp: the optical depth at every node of the light's
/// grid (core/render/light_grid.h), 3 per node, node (a, b, c) at (c·ny + b)·nx + a.
template <typename Scalar>
struct LightDepthGrid {
    LightGrid grid;
    std::vector<Scalar> depth;
    /// Trilinear between nodes at index-space point p, as lighting.glsl's lightDepthAt.
    Vec3T<Scalar> at(const Vec3T<Scalar>& p) const;
};
template <typename Scalar>
LightDepthGrid<Scalar> lightDepthGrid(const Volume& volume, const Vec3d& lightDirection, double stepVoxels);

/// Optical depth toward the light at one point, by any of the methods above.
template <typename Scalar>
class LightDepthLookup {
public:
    LightDepthLookup(const Volume& volume, const Vec3d& lightDirection, double stepVoxels, LightDepthMethod method);
    Vec3T<Scalar> at(const Vec3T<Scalar>& p) const;

private:
    const Volume& m_volume;
    Vec3d m_direction;
    double m_step;
    LightDepthMethod m_method;
    LightDepthGrid<Scalar> m_grid;        // Grid
    std::vector<Scalar> m_voxelCentres;   // VoxelCentres: 3 per voxel
};

}  // namespace volstyle::core::cpu_ref

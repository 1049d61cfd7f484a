#pragma once
/// \file reference_renderer.h
/// A straightforward CPU oracle of the GL renderer (STYLE §3.7): the same image formation, the same
/// segment quadrature and the same light-depth volume, in templated precision (double in tests),
/// with plain loops and no skipping or early termination. Slow: for tiny volumes and images.

#include "core/image/image.h"
#include "core/render/light_grid.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/volume/volume.h"

namespace volstyle::core::cpu_ref {

/// How the oracle gets the optical depth toward a light at a sample point p.
enum class LightDepthMethod {
    Grid,          ///< as the GL path: a march from p over its first node spans, then the light-aligned grid
    GridAlone,     ///< the grid alone, rows a voxel apart, trilinear (before issue #34; the lobes' volumes)
    Exact,         ///< a march from p itself to the box (the quantity the grids approximate)
    VoxelCentres,  ///< a march from every voxel centre, trilinear between them (before issue #10)
};

/// `lightStepVoxels` (> 0): the step of LightDepthMethod::Exact's marches toward the lights, finer
/// than the view's to get the exact light integral; default the view's step.
template <typename Scalar>
Image renderReference(const Volume& volume, const Camera& camera, const Lighting& lighting,
                      double stepVoxels, LightDepthMethod method = LightDepthMethod::Grid, double lightStepVoxels = 0);

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
    const Volume* volume = nullptr;
    double stepVoxels = 0.5;
    /// The optical depth at index-space point p as lighting.glsl's lightDepthAt gets it: marched
    /// from p over its first node spans, then the grid's depth where the march stopped.
    Vec3T<Scalar> at(const Vec3T<Scalar>& p) const;
    /// Trilinear between nodes at p (the grid alone, as lobe_volume.comp reads it).
    Vec3T<Scalar> interpolated(const Vec3T<Scalar>& p) const;
    /// At p on a node plane, as lighting.glsl's lightDepthOnPlane reads it: bilinear for a light
    /// along a voxel axis, else a Catmull–Rom spline over 4×4 nodes held to the nearest 2×2's range.
    Vec3T<Scalar> onPlane(const Vec3T<Scalar>& p) const;
};
/// `across` ≤ 0: the spacing the GL renderer picks for this volume's lights (lightGridAcross).
template <typename Scalar>
LightDepthGrid<Scalar> lightDepthGrid(const Volume& volume, const Vec3d& lightDirection, double stepVoxels,
                                      double across = 0, double along = kLightGridSpacing);

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
    LightDepthGrid<Scalar> m_grid;        // Grid, GridAlone
    std::vector<Scalar> m_voxelCentres;   // VoxelCentres: 3 per voxel
};

}  // namespace volstyle::core::cpu_ref

#pragma once
/// \file reference_renderer.h
/// A straightforward CPU oracle of the GL renderer (STYLE §3.7): the same image formation, the same
/// segment quadrature and the same light-depth volume, in templated precision (double in tests),
/// with plain loops and no skipping or early termination. Slow: for tiny volumes and images.

#include "core/image/image.h"
#include "core/render/params.h"
#include "core/volume/volume.h"

namespace volstyle::core::cpu_ref {

template <typename Scalar>
Image renderReference(const Volume& volume, const Camera& camera, const Lighting& lighting,
                      double stepVoxels);

/// Optical depth toward `lightDirection` (world, toward the light) from every voxel centre,
/// RGB per voxel: the light-depth volume of light_depth.comp.
template <typename Scalar>
std::vector<Scalar> lightDepthVolume(const Volume& volume, const Vec3d& lightDirection, double stepVoxels);

}  // namespace volstyle::core::cpu_ref

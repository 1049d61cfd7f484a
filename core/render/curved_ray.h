#pragma once
/// \file curved_ray.h
/// Rays through a continuously varying refractive index (issue #16, the TVCG paper Sec. 5.2): the
/// ray equation d/ds (n dx/ds) = ∇n, written as the first-order system in the state (x, v) with
/// v = n dx/ds (so |v| = n):
///     dx/ds = v / n(x),      dv/ds = ∇n(x).
/// The paper steps it with Euler forward (after Ihrke et al.'s eikonal rendering); the explicit
/// midpoint and classical Runge–Kutta schemes are here too, and tests/unit/curved_ray_test.cpp
/// measures each one's error against closed forms (a Luneburg lens focusing a parallel beam,
/// Bouguer's invariant n·|x × dx/ds| of a radial index). GL-free; the CPU reference the GPU
/// tracer will be checked against.

#include <functional>
#include <memory>
#include <vector>

#include "core/math/vec.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// n(x) and its gradient.
struct IndexField {
    std::function<double(const Vec3d&)> n;
    std::function<Vec3d(const Vec3d&)> gradient;
};

enum class RayScheme { EulerForward, Midpoint, RungeKutta4 };

struct RayState {
    Vec3d x;  ///< position
    Vec3d v;  ///< n · the unit direction
};

/// One step of arc length h.
RayState stepRay(const IndexField& field, const RayState& s, double h, RayScheme scheme);

/// Traces from `origin` along the unit `direction` in steps of h until `done(state)` or `maxLength`
/// of arc; the visited states, the first one the start.
std::vector<RayState> traceRay(const IndexField& field, const Vec3d& origin, const Vec3d& direction, double h, double maxLength,
                               RayScheme scheme, const std::function<bool(const RayState&)>& done);

/// A sphere of radius R at the origin whose index is the Luneburg lens's, n = sqrt(2 − (r/R)²)
/// inside and 1 outside: every ray of a parallel beam comes to a focus on the far side of the sphere.
IndexField luneburgLens(double radius);

/// A sphere of index `inside` in a medium of 1, its boundary a smooth step of width `width` around
/// the radius (a "sharp-ish" glass ball: Snell's law holds across it as the width goes to 0).
IndexField smoothSphere(double radius, double inside, double width);

/// A volume's `refractive_index` grid as a field: trilinear between voxel centres (clamped to the
/// edge voxels inside the voxels' box, as every grid of a volume), 1 outside the box, and the exact
/// gradient of that interpolant (per cell, carried to world space). Throws InvalidArgument when
/// the volume has no refractive index. The volume must outlive the field.
IndexField indexFieldOf(const Volume& volume);
/// The same over a grid of n.x·n.y·n.z values (x fastest) placed by `worldFromIndex`, or a sparse
/// volume's stored voxels when `bricks` is given (issue #39: its layout says where each voxel is);
/// the field shares both.
IndexField indexFieldOf(std::shared_ptr<const std::vector<float>> grid, Int3 n, const Mat4& worldFromIndex,
                        std::shared_ptr<const BrickLayout> bricks = nullptr);

}  // namespace volstyle::core

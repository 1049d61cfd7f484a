#pragma once
/// \file curved_paths.h
/// The view rays of a camera bent by a volume's refractive index (issue #16, the TVCG paper Sec.
/// 5.2): each pixel's ray is traced once through the voxels' box with the ray equation
/// (curved_ray.h) and kept as a polyline — the renderer and the solver's W and Wᵀ then march the
/// same straight pieces (common/march.glsl, VOLSTYLE_CURVED), so the adjoint identity holds
/// exactly and a solve traces each view once. GL-free; the GL side uploads these as buffers.
///
/// Conventions: the index is 1 outside the box and the trilinear interpolant of the grid inside
/// it (clamped to the edge voxels), so the box's faces do not refract (keep n = 1 at the border).
/// Rays are straight until they enter the box and after they leave it. Where the index is flat
/// (a brick of 8³ voxels whose values and one-voxel apron are all equal, so ∇n = 0 in it) the ray
/// crosses in one straight piece; collinear pieces merge.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/base/work_budget.h"
#include "core/render/curved_ray.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// A volume's refractive-index grid, kept for tracing, with its flat bricks. A sparse volume's grid
/// is kept as it is stored (issue #39): its inactive bricks read the background and are flat.
class RefractiveGrid {
public:
    /// The volume's grid, or null when it has none or it is constant (rays stay straight: the
    /// straight-ray code path is used, unchanged).
    static std::shared_ptr<const RefractiveGrid> of(const Volume& volume);

    Int3 dims() const { return m_dims; }
    const Mat4& worldFromIndex() const { return m_worldFromIndex; }
    const Mat4& indexFromWorld() const { return m_indexFromWorld; }
    /// A hash of the grid and its placement: paths are cached under it.
    size_t hash() const { return m_hash; }
    /// n and its world gradient (curved_ray.h's indexFieldOf).
    const IndexField& field() const { return m_field; }
    /// Whether ∇n = 0 everywhere in the brick holding index-space point p (and which brick).
    bool flatAt(const Vec3d& p) const;
    int brickOf(const Vec3d& p, Int3* brick) const;

private:
    explicit RefractiveGrid(const Volume& volume);
    std::shared_ptr<const std::vector<float>> m_values;
    std::shared_ptr<const BrickLayout> m_layout;  // a sparse volume's (issue #39: m_values are its stored voxels), else null
    Int3 m_dims;
    Mat4 m_worldFromIndex, m_indexFromWorld;
    IndexField m_field;
    std::vector<uint8_t> m_flat;  // per brick of 8³ voxels: 1 when flat
    Int3 m_bricks;
    size_t m_hash = 0;
};

struct PathVertex {
    float x, y, z;  ///< index-space position
    float t;        ///< arc length from the eye (world units)
};

/// One polyline per pixel (row 0 at the top, as the march's pixels).
struct ViewPaths {
    int width = 0, height = 0;
    std::vector<uint32_t> start;        ///< width·height + 1: pixel p's vertices are [start[p], start[p+1])
    std::vector<PathVertex> vertices;   ///< none for a ray that misses the box
    /// width·height: the world direction each ray leaves the box in (xyz unit, w 1), from the ray
    /// equation's state, not from the last piece's two float32 ends: where a ray leaves near a
    /// vertex its last piece can be 1e-5 voxels long, and its direction noise (issue #34: a
    /// speck 0.057 rad off behind a Luneburg lens). w 0 for a ray that misses the box.
    std::vector<std::array<float, 4>> exitDirection;
    size_t bytes() const {
        return start.size() * sizeof(uint32_t) + vertices.size() * sizeof(PathVertex) + exitDirection.size() * 4 * sizeof(float);
    }
};

struct PathTracing {
    /// Step of the ray equation, in voxels (world: times the smallest voxel side).
    double stepVoxels = 0.5;
    /// Classical Runge–Kutta by default. On trilinear grids (whose gradient jumps at cell faces)
    /// no scheme keeps its full order, but measured through a noisy glass ball (bench/refraction,
    /// docs/REFRACTION.md) RK4's error falls steadily with the step and at the march's default
    /// half voxel is 6× below the midpoint rule's and 2× below Euler forward's (the paper's), for
    /// 1.7× the midpoint's trace time — paid once per view, as the paths are cached.
    RayScheme scheme = RayScheme::RungeKutta4;
    /// Refused (OverBudget) above this many bytes of vertices.
    size_t maxBytes = size_t(512) << 20;
};

/// Traces every pixel of `camera` through `grid` (on all cores; `budget` checked between rows).
ViewPaths traceViewPaths(const RefractiveGrid& grid, const Camera& camera, const PathTracing& tracing = {},
                         const WorkBudget& budget = WorkBudget());

/// One pixel's path (world positions of its vertices) — for tests and the CPU oracle — and, when
/// `exitDirection` is given, the world direction it leaves in (its own direction if it misses).
std::vector<PathVertex> traceViewPath(const RefractiveGrid& grid, const Vec3d& eye, const Vec3d& direction, double nearDist,
                                      double farDist, const PathTracing& tracing = {}, Vec3d* exitDirection = nullptr);

}  // namespace volstyle::core

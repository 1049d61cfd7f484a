#pragma once
/// \file environment_lobes.h
/// Environment lighting as a basis of N directional lobes (SPEC §8; TVCG Sec. 4.4): the sphere (or
/// its upper half) split into N cells of equal solid angle around the points of a Fibonacci
/// lattice, each cell a "disc light" whose radiance is constant over it and whose light reaches
/// the volume from the cell's centre direction. A lat-long map is fitted to the basis by
/// projection (the solid-angle weighted mean of the map over each cell, the L2 projection onto
/// piecewise-constant cells), and a set of lobe radiances is written back as a lat-long map that
/// the projection reads back exactly. GL-free: the renderer, the solver, the CPU oracle and the
/// protocol all use it.
///
/// Lat-long convention (the background's, lighting.glsl): u = 0.5 + atan2(ω.x, −ω.z)/2π,
/// v = acos(ω.y)/π, so −z is the image centre and +y the top row (Blender's world texture with the
/// same orientation: docs/LIGHTING.md).

#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/math/vec.h"

namespace volstyle::core {

enum class LobeDomain { Sphere, UpperHemisphere };

constexpr int kMinLobes = 1;
constexpr int kMaxLobes = 256;

struct LobeBasis {
    LobeDomain domain = LobeDomain::Sphere;
    std::vector<Vec3d> directions;  ///< unit, world space, toward the light

    /// N lobes over `domain` (N in [kMinLobes, kMaxLobes]; throws InvalidArgument otherwise).
    static LobeBasis make(int count, LobeDomain domain);

    int size() const { return int(directions.size()); }
    /// Each lobe's solid angle: its cell measured on a kProjectionWidth-wide lat-long grid (about
    /// 4π/N, or 2π/N over the upper hemisphere; they sum to 4π or 2π). Measured once per basis.
    std::vector<double> solidAngles() const;
    /// The lobe whose cell holds `direction` (the nearest lobe centre), or -1 below the horizon of
    /// an upper-hemisphere basis.
    int cellOf(const Vec3d& direction) const;
    /// For each lobe, its `k` nearest other lobes by angle (for the smoothness regularizer).
    std::vector<std::vector<int>> neighbours(int k) const;
    /// Names the basis in cache keys: count and domain (the lattice is deterministic).
    std::string key() const;
};

/// The lobes' light volumes' grid (core/render/lobe_volumes.h) for a volume of `volumeDims`
/// voxels: the volume's own dims when its longest axis has at most `resolution` voxels, else
/// scaled so the longest has `resolution` (each axis at least 2 nodes).
Int3 lobeGridDims(Int3 volumeDims, int resolution);

/// World direction at lat-long coordinates (u, v) ∈ [0,1]² (the convention above), and back.
Vec3d latLongDirection(double u, double v);
void latLongCoordinates(const Vec3d& direction, double& u, double& v);

/// The map's mean radiance over each lobe's cell, weighted by texel solid angle (maps larger than
/// kProjectionWidth × kProjectionWidth/2 are first averaged down to that). A cell no texel centre
/// falls in (a tiny map) takes the map's bilinear value in the lobe's direction.
std::vector<Vec3d> projectEnvironment(const LobeBasis& basis, const Image& latLong);
constexpr int kProjectionWidth = 512;

/// Lobe radiances as a width × height lat-long map: every texel the radiance of the cell its
/// centre falls in (0 below the horizon of an upper-hemisphere basis), alpha 1. At most
/// kProjectionWidth wide, projectEnvironment reads it back exactly.
Image lobesToLatLong(const LobeBasis& basis, const std::vector<Vec3d>& radiance, int width, int height);

/// The map's bilinear value along `direction` (longitude wraps, latitude clamps), as the
/// background lookup in lighting.glsl.
Vec3d sampleLatLong(const Image& latLong, const Vec3d& direction);

/// Why `latLong` cannot be a latitude-longitude map, or "" if it can: empty, not 2:1 (one pixel
/// of slack for odd sizes), or holding non-finite or negative RGB values.
std::string latLongMapProblem(const Image& latLong);
/// Only the size part of latLongMapProblem (cheap: Lighting::check runs it on every render).
std::string latLongShapeProblem(const Image& latLong);

}  // namespace volstyle::core

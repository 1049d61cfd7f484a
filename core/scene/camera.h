#pragma once
/// \file camera.h
/// The pinhole camera (SPEC §1): a scene value every engine and the protocol share. GL-free.

#include <optional>
#include <utility>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/field_problem.h"

namespace volstyle::core {

/// Pinhole camera (SPEC §1). Pixel (0,0) is the top-left pixel; rays pass through pixel centres.
struct Camera {
    Vec3d eye{0, 0, 3};
    Vec3d target{0, 0, 0};
    Vec3d up{0, 1, 0};
    double fovYDeg = 40;
    int width = 480;
    int height = 480;
    double nearDist = 0;                  ///< rays start this far from the eye (world units)
    double farDist = 1e30;                ///< and end here (the "surface depth" when no mesh)

    /// Every problem as (field, message), fields named as in the JSON API (`fov_y_deg`): eye =
    /// target, up parallel to the view direction, fov outside (0,180), sizes outside [1, 8192],
    /// near/far not 0 <= near < far, non-finite values.
    std::vector<FieldProblem> check() const;
    /// Throws InvalidArgument listing check()'s problems.
    void validate() const;

    /// Orthonormal camera frame: forward (eye->target), right, and true up.
    struct Frame {
        Vec3d forward, right, up;
    };
    Frame frame() const;

    /// World-space direction (unit length) of the ray through the centre of pixel (px, py).
    Vec3d rayDirection(double px, double py) const;
    /// tan(fov_y / 2): the image plane's half-height at distance 1.
    double tanHalfFov() const;
    /// The pixel a world point projects into (the inverse of rayDirection), or nothing when the
    /// point is behind the camera or outside the image.
    struct Pixel {
        int x, y;
    };
    std::optional<Pixel> project(const Vec3d& world) const;
    bool operator==(const Camera&) const = default;
};

/// The default view: 480×480 from +z, slightly above the horizon, framing [-1, 1]³.
Camera defaultCamera();
/// The default camera's view (from the front, slightly above) moved so that the box's bounding
/// sphere fills the frame: any volume is in view, whatever its size and place.
Camera framingCamera(const std::pair<Vec3d, Vec3d>& worldBounds);

}  // namespace volstyle::core

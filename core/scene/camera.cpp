#include "core/scene/camera.h"

#include <cmath>
#include <numbers>

namespace volstyle::core {
namespace {

bool isFinite(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

std::vector<FieldProblem> Camera::check() const {
    std::vector<FieldProblem> out;
    if (!isFinite(eye)) out.push_back({"eye", "must be finite"});
    if (!isFinite(target)) out.push_back({"target", "must be finite"});
    if (!isFinite(up) || length(up) < 1e-12) out.push_back({"up", "must be a finite non-zero vector"});
    if (out.empty()) {
        Vec3d view = target - eye;
        if (!isFinite(view) || !std::isfinite(length(view)) || !std::isfinite(length(up))) {
            // e.g. eye 1e308 and target −1e308: the direction overflows and the frame would be NaN.
            out.push_back({"target", "is too far from eye (the view direction overflows); keep coordinates below 1e150"});
        } else if (length(view) < 1e-9) {
            out.push_back({"target", "must differ from eye"});
        } else if (length(cross(normalize(view), normalize(up))) < 1e-6) {
            out.push_back({"up", "must not be parallel to the view direction (target - eye)"});
        }
    }
    if (!(fovYDeg > 0 && fovYDeg < 180)) out.push_back({"fov_y_deg", "must be in (0, 180)"});
    if (width < 1 || width > 8192) out.push_back({"width", "must be in [1, 8192]"});
    if (height < 1 || height > 8192) out.push_back({"height", "must be in [1, 8192]"});
    if (!(nearDist >= 0) || !std::isfinite(nearDist)) out.push_back({"near", "must be finite and >= 0"});
    if (!(farDist > nearDist)) out.push_back({"far", "must be greater than near"});
    return out;
}

void Camera::validate() const { throwIfAny("camera", check()); }

Camera::Frame Camera::frame() const {
    Frame f;
    f.forward = normalize(target - eye);
    f.right = normalize(cross(f.forward, up));
    f.up = cross(f.right, f.forward);
    return f;
}

Vec3d Camera::rayDirection(double px, double py) const {
    // Pixel centre (px+0.5, py+0.5) mapped to [-1,1]² with y up; the image plane sits at distance
    // 1 with half-height tan(fov/2).
    Frame f = frame();
    double tanHalf = tanHalfFov();
    double aspect = double(width) / double(height);
    double sx = (2.0 * (px + 0.5) / width - 1.0) * tanHalf * aspect;
    double sy = (1.0 - 2.0 * (py + 0.5) / height) * tanHalf;
    return normalize(f.forward + f.right * sx + f.up * sy);
}

double Camera::tanHalfFov() const { return std::tan(fovYDeg * std::numbers::pi / 360.0); }

std::optional<Camera::Pixel> Camera::project(const Vec3d& world) const {
    const Frame f = frame();
    const Vec3d rel = world - eye;
    const double z = dot(rel, f.forward);
    if (!(z > 0)) return std::nullopt;
    const double tanHalf = tanHalfFov();
    const double x = dot(rel, f.right) / (z * tanHalf * width / height), y = dot(rel, f.up) / (z * tanHalf);
    const double px = std::floor((x + 1) / 2 * width), py = std::floor((1 - y) / 2 * height);
    if (!(px >= 0 && py >= 0 && px < width && py < height)) return std::nullopt;
    return Pixel{int(px), int(py)};
}

Camera defaultCamera() {
    Camera c;
    c.eye = {0.0, 0.15, 3.4};
    c.target = {0.0, -0.05, 0.0};
    c.fovYDeg = 38;
    c.width = c.height = 480;
    return c;
}

Camera framingCamera(const std::pair<Vec3d, Vec3d>& worldBounds) {
    Camera c = defaultCamera();
    const Vec3d centre = (worldBounds.first + worldBounds.second) * 0.5;
    const double radius = 0.5 * length(worldBounds.second - worldBounds.first);
    const double halfFov = 0.5 * c.fovYDeg * std::numbers::pi / 180.0;
    const Vec3d direction = normalize(defaultCamera().eye - defaultCamera().target);
    c.target = centre;
    c.eye = centre + direction * (radius / std::sin(halfFov));
    return c;
}

}  // namespace volstyle::core

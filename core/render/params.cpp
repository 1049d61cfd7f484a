#include "core/render/params.h"

#include <cmath>
#include <deque>
#include <mutex>
#include <numbers>
#include <sstream>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

bool isFinite(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void throwIfAny(const char* what, const std::vector<FieldProblem>& problems) {
    if (problems.empty()) return;
    std::string msg;
    for (const auto& p : problems) msg += (msg.empty() ? "" : "; ") + std::string(what) + "." + p.field + ": " + p.message;
    throw InvalidArgument(msg);
}

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

std::vector<FieldProblem> Lighting::check() const {
    std::vector<FieldProblem> out;
    if (lights.size() > size_t(kMaxLights))
        out.push_back({"lights", "at most " + std::to_string(kMaxLights) + " lights are supported"});
    for (size_t i = 0; i < lights.size(); ++i) {
        const auto& l = lights[i];
        std::string name = "lights/" + std::to_string(i);
        if (!isFinite(l.direction) || length(l.direction) < 1e-12)
            out.push_back({name + "/direction", "must be a finite non-zero vector"});
        if (!isFinite(l.irradiance) || minComponent(l.irradiance) < 0)
            out.push_back({name + "/irradiance", "must be finite and >= 0"});
    }
    if (!isFinite(background.color) || minComponent(background.color) < 0)
        out.push_back({"background", "must be finite and >= 0"});
    if (phase.type == PhaseType::HenyeyGreenstein && !(phase.g > -1 && phase.g < 1))
        out.push_back({"phase/g", "must be in (-1, 1)"});
    if (background.environment)
        if (std::string why = latLongShapeProblem(*background.environment); !why.empty()) out.push_back({"background/environment", why});
    if (background.plate && background.plate->empty()) out.push_back({"background/plate", "the background plate is empty"});
    if (background.fromLobes && !environment.active())
        out.push_back({"background/environment", "\"lobes\" shows the environment light's lobes, but there is none (environment.lobes is 0)"});
    if (background.fromLobes && background.environment)
        out.push_back({"background/environment", "is either a map or \"lobes\", not both"});
    const EnvironmentLight& env = environment;
    if (env.lobes < 0 || env.lobes > kMaxLobes)
        out.push_back({"environment/lobes", "must be in [" + std::to_string(kMinLobes) + ", " + std::to_string(kMaxLobes) + "] (or 0: no environment light)"});
    if (!std::isfinite(env.strength) || env.strength < 0) out.push_back({"environment/strength", "must be finite and >= 0"});
    if (env.lightVolumeResolution < kMinLightVolumeResolution || env.lightVolumeResolution > kMaxLightVolumeResolution)
        out.push_back({"environment/light_volume_resolution", "must be in [" + std::to_string(kMinLightVolumeResolution) + ", " +
                                                                  std::to_string(kMaxLightVolumeResolution) + "]"});
    if (env.active() && env.radiance.empty() && !env.map)
        out.push_back({"environment", "needs a map or a radiance per lobe"});
    if (!env.radiance.empty() && env.radiance.size() != size_t(env.lobes))
        out.push_back({"environment/radiance", "has " + std::to_string(env.radiance.size()) + " entries for " + std::to_string(env.lobes) + " lobes"});
    for (size_t i = 0; i < env.radiance.size(); ++i)
        if (!isFinite(env.radiance[i]) || minComponent(env.radiance[i]) < 0) {
            out.push_back({"environment/radiance/" + std::to_string(i), "must be finite and >= 0"});
            break;
        }
    if (env.map)
        if (std::string why = latLongShapeProblem(*env.map); !why.empty()) out.push_back({"environment/map", why});
    // The product must stay a finite float on the GPU.
    for (const Vec3d& r : env.radiance)
        if (isFinite(r) && maxComponent(r) * env.strength > 1e30) {
            out.push_back({"environment/strength", "times the largest radiance must be at most 1e30"});
            break;
        }
    return out;
}

void Lighting::validate() const { throwIfAny("lighting", check()); }

std::vector<Vec3d> lobeRadiance(const EnvironmentLight& env) {
    std::vector<Vec3d> radiance = env.radiance;
    if (radiance.empty() && env.active() && env.map) {
        // A projection at 256 lobes reads 512×256 blocks against every lobe (~30 ms): keep the
        // last few, holding their maps so an address is never reused while remembered.
        struct Projected {
            std::shared_ptr<const Image> map;
            std::string basis;
            std::vector<Vec3d> radiance;
        };
        static std::mutex mutex;
        static std::deque<Projected> recent;
        const LobeBasis basis = env.basis();
        std::lock_guard lock(mutex);
        for (const Projected& p : recent)
            if (p.map == env.map && p.basis == basis.key()) radiance = p.radiance;
        if (radiance.empty()) {
            radiance = projectEnvironment(basis, *env.map);
            recent.push_front({env.map, basis.key(), radiance});
            if (recent.size() > 8) recent.pop_back();
        }
    }
    for (Vec3d& r : radiance) r *= env.strength;
    return radiance;
}

Lighting defaultLighting() {
    Lighting l;
    l.lights = {{{-0.55, 0.65, 0.55}, {26.0, 24.5, 22.0}},
                {{0.0, 1.0, 0.0}, {3.0, 4.0, 6.0}},
                {{0.2, -1.0, 0.1}, {1.6, 1.5, 1.3}}};
    l.background.color = {0.32, 0.50, 0.82};
    l.phase = {PhaseType::HenyeyGreenstein, 0.25};
    return l;
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

std::optional<FieldProblem> stepProblem(double stepVoxels) {
    if (stepVoxels >= kMinStepVoxels && stepVoxels <= kMaxStepVoxels) return std::nullopt;
    std::ostringstream m;
    m << "must be in [" << kMinStepVoxels << ", " << kMaxStepVoxels << "] voxels, got " << stepVoxels;
    return FieldProblem{"step", m.str()};
}

void RenderSettings::validate() const {
    std::vector<FieldProblem> out;
    if (auto p = stepProblem(stepVoxels)) out.push_back(*p);
    if (!(terminationThreshold >= 0 && terminationThreshold < 1))
        out.push_back({"termination_threshold", "must be in [0, 1)"});
    throwIfAny("render", out);
}

}  // namespace volstyle::core

#include "core/scene/lighting.h"

#include <cmath>
#include <deque>
#include <mutex>
#include <numbers>

namespace volstyle::core {
namespace {

bool isFinite(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

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

}  // namespace volstyle::core

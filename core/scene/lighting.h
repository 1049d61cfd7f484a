#pragma once
/// \file lighting.h
/// The lighting of a scene (SPEC §1, §8): directional lights, the background, the environment's
/// lobes and the phase function. GL-free.

#include <memory>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/math/vec.h"
#include "core/scene/environment_lobes.h"
#include "core/scene/field_problem.h"

namespace volstyle::core {

/// A directional light (the sun): `direction` points from the scene toward the light.
struct DirectionalLight {
    Vec3d direction{0.4, 0.8, 0.3};
    Vec3d irradiance{1, 1, 1};  ///< E_l, RGB
};

enum class PhaseType { Isotropic, HenyeyGreenstein };

/// Phase function p(cos) with cos = ω_l·(−ω) (SPEC §1). Henyey–Greenstein uses pbrt's sign
/// convention, so g > 0 scatters forward: bright when looking toward the light.
struct Phase {
    PhaseType type = PhaseType::Isotropic;
    double g = 0;  ///< HG asymmetry in (-1, 1)
    bool operator==(const Phase&) const = default;
};

/// Radiance arriving from behind the volume: a constant colour or a lat-long environment map.
struct Background {
    Vec3d color{0, 0, 0};
    /// Latitude-longitude map, looked up by ray direction: u = 0.5 + atan2(ω.x, −ω.z)/2π
    /// (so −z is the centre of the image), v = acos(ω.y)/π (+y is the top row). Linear RGB.
    std::shared_ptr<const Image> environment;
    /// A per-view background image (a plate, SPEC §1), pixel-aligned with the camera it is
    /// rendered with (the same size): replaces the colour and the map for that render. Set per
    /// view (SolveView::lightingFor), never stored in a session's lighting.
    std::shared_ptr<const Image> plate;
    /// The environment light's lobes seen directly (`"environment": "lobes"`): each direction has
    /// the radiance of the lobe whose cell holds it (below a hemisphere basis: `color`), so a
    /// lights solve solves the background too. Needs an active environment light.
    bool fromLobes = false;
};

constexpr int kMaxLights = 4;

/// Environment lighting (SPEC §8): the sphere (or its upper half) as N lobes of constant radiance
/// (core/render/environment_lobes.h), each lighting the volume like a directional light from its
/// centre with irradiance radiance × its cell's solid angle, through a light volume of its own
/// (the transmittance toward it, core/render/lobe_volumes.h). The `lights` unknown solves for
/// `radiance`.
struct EnvironmentLight {
    int lobes = 0;  ///< 0: the environment does not light the volume
    LobeDomain domain = LobeDomain::Sphere;
    /// Per lobe, linear RGB radiance; empty: projected from `map` (lobeRadiance()).
    std::vector<Vec3d> radiance;
    std::shared_ptr<const Image> map;  ///< the lat-long map it is fitted to, if any
    double strength = 1;                ///< multiplies the radiance
    /// Nodes of the light volumes' grid along the volume's longest axis (the others in
    /// proportion); the extinction's own dims when smaller.
    int lightVolumeResolution = 64;

    bool active() const { return lobes > 0; }
    LobeBasis basis() const { return LobeBasis::make(lobes, domain); }
    /// Radiances as they are to be used from now on (a solve's): no map, strength 1.
    void setRadiance(std::vector<Vec3d> perLobe) {
        radiance = std::move(perLobe);
        map = nullptr;
        strength = 1;
    }
};
constexpr int kMinLightVolumeResolution = 2;
constexpr int kMaxLightVolumeResolution = 256;

/// The lobes' radiances times the strength: `radiance` as given, or the map projected onto the
/// basis (remembered for the last few maps, so a render does not project it again).
std::vector<Vec3d> lobeRadiance(const EnvironmentLight& environment);

struct Lighting {
    std::vector<DirectionalLight> lights = std::vector<DirectionalLight>(1);  ///< at most kMaxLights (one default sun; no initializer list: GCC 12 false -Wmaybe-uninitialized)
    Background background;
    EnvironmentLight environment;
    Phase phase;

    std::vector<FieldProblem> check() const;
    void validate() const;  ///< throws InvalidArgument listing check()'s problems
};

/// The default outdoor look (docs/examples/lighting.json): a warm sun from the upper left front,
/// a blue sky light from above, a faint ground bounce from below, a sky-blue background and mildly
/// forward Henyey–Greenstein scattering. Tuned so a white cloud's lit side is about 0.9.
Lighting defaultLighting();

}  // namespace volstyle::core

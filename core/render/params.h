#pragma once
/// \file params.h
/// GL-free value types that describe a rendering (SPEC §1): camera, lighting and settings.
/// protocol/ may include this header; it never touches GL.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/math/vec.h"
#include "core/render/environment_lobes.h"

namespace volstyle::core {

/// A field of a parameter struct and what is wrong with it (protocol/ maps it to a JSON Pointer).
struct FieldProblem {
    std::string field;    ///< e.g. "fov_y_deg", "lights/0/irradiance"
    std::string message;
};

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
};

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

/// Quality/speed knobs of the ray marcher.
/// The default outdoor look (docs/examples/lighting.json): a warm sun from the upper left front,
/// a blue sky light from above, a faint ground bounce from below, a sky-blue background and mildly
/// forward Henyey–Greenstein scattering. Tuned so a white cloud's lit side is about 0.9.
Lighting defaultLighting();

/// The default view: 480×480 from +z, slightly above the horizon, framing [-1, 1]³.
Camera defaultCamera();
/// The default camera's view (from the front, slightly above) moved so that the box's bounding
/// sphere fills the frame: any volume is in view, whatever its size and place.
Camera framingCamera(const std::pair<Vec3d, Vec3d>& worldBounds);

/// The march step's range, in voxels, for every march (renders, solves, previews): the one
/// place it is stated (stepProblem; the schema's solve_options.step says the same, checked by
/// tests/unit/schema_limits_test.cpp). Finer than 0.05 multiplies a solve's rows past any use.
inline constexpr double kMinStepVoxels = 0.05, kMaxStepVoxels = 8;
/// The problem with a march step (field "step"), if any.
std::optional<FieldProblem> stepProblem(double stepVoxels);

struct RenderSettings {
    double stepVoxels = 0.5;        ///< march step, in voxels of the extinction grid
    bool skipEmptySpace = true;     ///< jump over occupancy bricks with zero extinction
    /// Early ray termination budget ε. A ray stops once its transmittance T is below ε and the
    /// most it could still gather, T·L_max (L_max bounds emission + in-scattering + background),
    /// is below ε of what it has gathered — or once T < 1e-3·ε. So the radiance lost is below ε
    /// relative (alpha below ε absolute). 0 marches every ray to its end.
    double terminationThreshold = 1e-5;
    bool hardwareFilter = false;    ///< sample with the texture unit (fast, 8-bit weights on GPUs)
    /// One segment per voxel cell crossed (Amanatides–Woo) instead of equal steps of stepVoxels.
    bool exactTraversal = false;
    /// Follow the volume's refractive_index grid (issue #16). Off, or with no grid or a constant
    /// one, rays are straight and the straight-ray kernels run unchanged.
    bool refraction = true;

    void validate() const;
};

}  // namespace volstyle::core

#pragma once
// Homogeneous scenes with closed-form single-scattering answers, shared by the CPU-reference and
// GL tests (SPEC §5 accuracy tests).

#include <cmath>
#include <numbers>

#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/volume.h"

namespace volstyle::test {

/// The cube [-1,1]³ of `n`³ voxels with constant extinction σ and (optionally) emission E.
inline core::Volume constantCube(int n, float sigma, Vec3 emission = Vec3(0.0f)) {
    core::Volume v({n, n, n}, core::unitBoxWorldFromIndex({n, n, n}));
    for (float& s : v.extinction()) s = sigma;
    if (maxComponent(emission) > 0) {
        auto& e = v.ensureEmission();
        for (size_t i = 0; i < v.voxelCount(); ++i)
            e[3 * i] = emission.x, e[3 * i + 1] = emission.y, e[3 * i + 2] = emission.z;
    }
    return v;
}

/// A camera far up the +z axis with a narrow field: every ray crosses the cube front to back.
inline core::Camera axisCamera(int size = 7) {
    core::Camera c;
    c.eye = {0, 0, 6};
    c.target = {0, 0, 0};
    c.fovYDeg = 6;
    c.width = c.height = size;
    return c;
}

/// No lights: only emission and the background.
inline core::Lighting darkLighting(Vec3d background = {0, 0, 0}) {
    core::Lighting l;
    l.lights.clear();
    l.background.color = background;
    return l;
}

/// Emission and absorption along a ray of length s in the cube: E(1 − e^{−σs}) + L_bg e^{−σs}.
inline double cubeRadiance(double E, double Lbg, double sigma, const Vec3d& dir) {
    double s = 2.0 / std::abs(dir.z);
    return E * -std::expm1(-sigma * s) + Lbg * std::exp(-sigma * s);
}

/// A slab y ∈ [0, d] (d = 0.5), x,z ∈ [-1, 1], constant σ and albedo ρ, lit by a sun at θ from
/// the zenith, seen from straight above. Anisotropic voxels (hy ≠ hx) on purpose.
struct SlabScene {
    int nx = 24, ny = 64, nz = 24;
    double d = 0.5;
    double sigma = 4.0;
    double albedo = 0.8;
    double thetaDeg = 45;
    double irradiance = 3.0;
    double g = 0.3;

    double hy() const { return d / ny; }
    Vec3d sunDirection() const {
        double t = thetaDeg * std::numbers::pi / 180;
        return {std::sin(t), std::cos(t), 0};
    }
    core::Volume volume() const {
        double hx = 2.0 / nx, hz = 2.0 / nz;
        Mat4 xf = Mat4::translate({-1 + hx / 2, hy() / 2, -1 + hz / 2}) * Mat4::scale({hx, hy(), hz});
        core::Volume v({nx, ny, nz}, xf);
        for (float& s : v.extinction()) s = float(sigma);
        for (float& a : v.ensureAlbedo()) a = float(albedo);
        return v;
    }
    core::Lighting lighting() const {
        core::Lighting l;
        l.lights = {{sunDirection(), Vec3d(irradiance)}};
        l.background.color = {0, 0, 0};
        l.phase = {core::PhaseType::HenyeyGreenstein, g};
        return l;
    }
    core::Camera camera() const {
        core::Camera c;
        c.eye = {0, 3, 0};
        c.target = {0, 0, 0};
        c.up = {0, 0, -1};
        c.fovYDeg = 4;
        c.width = c.height = 5;
        return c;
    }
    /// Henyey–Greenstein, pbrt's sign: cos = ω_l·(−ω), g > 0 scatters forward.
    double phase(double cosTheta) const {
        double denom = 1 + g * g + 2 * g * cosTheta;
        return (1 - g * g) / (4 * std::numbers::pi * denom * std::sqrt(denom));
    }
    /// ∫₀ˢ e^{−σt} σ ρ p E e^{−σ t a / cosθ} dt = ρ p E (1 − e^{−σ s k}) / k, with a = |ω_y|,
    /// s = d / a, k = 1 + a / cosθ (the light path from depth u = t a is u / cosθ long).
    double radiance(const Vec3d& dir) const {
        double a = std::abs(dir.y), s = d / a, cosT = sunDirection().y;
        double k = 1 + a / cosT;
        return albedo * phase(dot(sunDirection(), -dir)) * irradiance * -std::expm1(-sigma * s * k) / k;
    }
    /// The renderer stores optical depth toward the sun at voxel centres and clamps it to the edge,
    /// so within half a voxel of the top and bottom faces it is off by at most σ (hy/2) / cosθ.
    /// Bound on the radiance error that causes: 2 · ρ p E σ (hy / 2a) (1 − e^{−σ hy / 2cosθ}).
    double errorBound(const Vec3d& dir) const {
        double a = std::abs(dir.y), cosT = sunDirection().y;
        return 2 * albedo * phase(dot(sunDirection(), -dir)) * irradiance * sigma * (hy() / (2 * a)) *
               -std::expm1(-sigma * hy() / (2 * cosT));
    }
};

}  // namespace volstyle::test

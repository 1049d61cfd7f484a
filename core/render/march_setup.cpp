#include "core/render/march_setup.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/render/derived_volumes.h"
#include "core/render/gl_convert.h"

namespace volstyle::core {
namespace {

/// The largest phase-function value: 1/4π, or HG at cos = −1 (pbrt's sign puts its peak there).
double maxPhase(const Phase& phase) {
    const double inv4pi = 1.0 / (4.0 * std::numbers::pi);
    if (phase.type == PhaseType::Isotropic) return inv4pi;
    double g = std::abs(phase.g);
    return inv4pi * (1 + g) / ((1 - g) * (1 - g));
}

/// An upper bound on the radiance a ray can gather per unit opacity (early termination):
/// L_m ≤ max L_e + max ρ · Σ p_max E_l (ρ ≤ 1, T_l ≤ 1); the background is bounded by its max.
double radianceBound(const GpuVolume& volume, const Lighting& lighting, const EnvironmentTexture* environment,
                     const MarchSetup& setup) {
    double bound = volume.maxEmission();
    for (const auto& l : lighting.lights) bound += maxPhase(lighting.phase) * maxComponent(l.irradiance);
    if (setup.lobes)
        for (int i = 0; i < setup.lobes->lobes; ++i) {
            const auto& d = setup.lobeParams.direction[i];
            const auto& r = setup.lobeParams.radiance[i];
            bound += maxPhase(lighting.phase) * d.w * std::max({r.x, r.y, r.z});
        }
    double background = environment ? environment->maxValue : maxComponent(lighting.background.color);
    for (int i = 0; setup.backgroundLobes && i < lighting.environment.lobes; ++i) {
        const auto& r = setup.lobeParams.radiance[i];
        background = std::max(background, double(std::max({r.x, r.y, r.z})));
    }
    return bound + background;
}

}  // namespace

MarchSetup prepareMarch(GpuDevice& device, GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                        const RenderSettings& settings, RenderStats& stats, const WorkBudget& budget) {
    updateOccupancy(device, volume, stats);

    // Lights with zero irradiance add nothing: leave them out of the variant.
    std::vector<const DirectionalLight*> lights;
    for (const auto& l : lighting.lights)
        if (maxComponent(l.irradiance) > 0) lights.push_back(&l);
    MarchSetup setup;
    for (const DirectionalLight* l : lights) setup.lightDepth.push_back(lightDepthVolume(device, volume, *l, settings, stats, budget));
    std::shared_ptr<const EnvironmentTexture> environment;
    if (const auto& plate = lighting.background.plate) {
        if (plate->width != camera.width || plate->height != camera.height)
            throw InvalidArgument("the background plate is " + std::to_string(plate->width) + "x" + std::to_string(plate->height) +
                                  " but the camera renders " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
        setup.plate = true;
    }
    if (const auto& image = setup.plate ? lighting.background.plate : lighting.background.environment) {
        environment = environmentTexture(device, image);
        setup.environment = std::shared_ptr<const gl::Texture>(environment, &environment->texture);  // shares ownership
    }

    // Camera and lighting parameters.
    layout::MarchParams& p = setup.params;
    p = volumeParams(volume, settings);
    const Camera::Frame f = camera.frame();
    p.eye = f4(camera.eye);
    p.camForward = f4(f.forward, camera.tanHalfFov());
    p.camRight = f4(f.right, double(camera.width) / double(camera.height));
    p.camUp = f4(f.up);
    p.rayRange = {float(camera.nearDist), float(std::min(camera.farDist, 3.0e38)), 0, 0};
    p.imageSize = {camera.width, camera.height, 0, 0};
    p.background = f4(lighting.background.color);
    p.phase = {lighting.phase.type == PhaseType::HenyeyGreenstein ? 1.0f : 0.0f, float(lighting.phase.g), 0, 0};
    for (size_t i = 0; i < lights.size(); ++i) {
        p.lightDirection[i] = f4(normalize(lights[i]->direction));
        p.lightIrradiance[i] = f4(lights[i]->irradiance);
        p.lightGridFromIndex[i] = toGl(setup.lightDepth[i]->grid.gridFromIndex);
        p.lightGridDims[i] = i4(setup.lightDepth[i]->grid.dims, setup.lightDepth[i]->grid.alongAxis ? 1 : 0);
    }
    // The environment's lobes: their parameters, the light volumes when any is lit (cached), and
    // the lobes as the background when asked (and no plate hides it).
    if (lighting.environment.active()) {
        const std::vector<Vec3d> radiance = lobeRadiance(lighting.environment);
        const LobeBasis basis = lighting.environment.basis();
        const std::vector<double> omega = basis.solidAngles();
        for (int i = 0; i < basis.size(); ++i) {
            setup.lobeParams.direction[i] = f4(basis.directions[size_t(i)], omega[size_t(i)]);
            setup.lobeParams.radiance[i] = f4(radiance[size_t(i)]);
        }
        if (lighting.background.fromLobes && !setup.plate) {
            setup.backgroundLobes = true;
            p.background.w = float(basis.domain == LobeDomain::Sphere ? basis.size() : -basis.size());
        }
        if (std::any_of(radiance.begin(), radiance.end(), [](const Vec3d& r) { return maxComponent(r) > 0; })) {
            setup.lobes = lobeLightVolumes(device, volume, basis, lighting.environment.lightVolumeResolution, settings, stats, budget);
            const LobeLightVolumes& lv = *setup.lobes;
            p.lobeGrid = {lv.dims.x, lv.dims.y, lv.dims.z, lv.lobes};
            p.lobeScale = {float(lv.dims.x) / float(volume.dims().x), float(lv.dims.y) / float(volume.dims().y),
                           float(lv.dims.z) / float(volume.dims().z), float(lv.channels)};
        }
    }
    p.march.z = float(radianceBound(volume, lighting, environment.get(), setup));
    setup.paths = refractedPaths(device, volume, camera, settings, stats, budget);
    return setup;
}

void bindMarch(GpuDevice& device, const GpuVolume& volume, const MarchSetup& setup) {
    device.setParams(setup.params);
    bindExtinction(volume);
    if (setup.environment) glBindTextureUnit(layout::kUnitEnvironment, setup.environment->id());
    for (size_t i = 0; i < setup.lightDepth.size(); ++i)
        glBindTextureUnit(GLuint(layout::kUnitLightDepth0 + i), setup.lightDepth[i]->texture.id());
    if (setup.lobes || setup.backgroundLobes) device.setParams(setup.lobeParams, layout::kBindingLobeParams);
    if (setup.lobes) glBindTextureUnit(layout::kUnitLobeTransmittance, setup.lobes->texture.id());
    if (setup.paths) bindRefractedPaths(*setup.paths);
}

}  // namespace volstyle::core

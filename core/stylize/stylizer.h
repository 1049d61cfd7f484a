#pragma once
/// \file stylizer.h
/// The light-shaft stylizer's engine (SPEC §7, the GI paper Sec. 3–4): rasterizes the light's
/// shadow map (depth and object ids) and the camera's G-buffer (normal, distance, colour) with GL,
/// then per pixel the average visibility V̄ along the view ray (Eq. 2) and the frame
///   L = L_surf e^{−σt s} + ρ p E (1 − e^{−σt s}) V̄        (directional light).
/// This first version: a directional light, the naive V̄ (N shadow-map lookups per ray, the
/// reference the accelerated methods are measured against), closing as the only manipulation,
/// no transfer function yet. GL-free header; GL thread only.

#include <memory>

#include "core/gpu/gpu_device.h"
#include "core/image/image.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

struct StylizeSettings {
    int steps = 256;  ///< shadow-map lookups per view ray for V̄ (naive method), 1–4096
    void validate() const;
};

/// A frame and its AOVs (SPEC §7 "Outputs"), all linear.
struct StylizedFrame {
    Image frame;              ///< RGBA, alpha 1
    Image scattering;         ///< L_scat before any transfer function (rgb)
    Image averageVisibility;  ///< V̄ ∈ [0, 1] in rgb
    Image linearDepth;        ///< s: distance to the first surface (or the camera's far), rgb
    Image shadowMap;          ///< the light's depth in [0, 1] (1: nothing), side shadow_map_size
    Image modifiedShadowMap;  ///< the same after the occluders' manipulations (what V̄ reads)
    double shadowMs = 0, gbufferMs = 0, shadeMs = 0, totalMs = 0;
};

class Stylizer {
public:
    explicit Stylizer(GpuDevice& device);
    ~Stylizer();
    Stylizer(const Stylizer&) = delete;
    Stylizer& operator=(const Stylizer&) = delete;

    /// Renders `scene` (validated first; InvalidArgument names the problem).
    StylizedFrame render(const StylizerScene& scene, const StylizeSettings& settings = {});

private:
    struct Gpu;
    GpuDevice& m_device;
    std::unique_ptr<Gpu> m_gpu;
};

/// The orthographic map from world space to the light's clip space [-1,1]³ that covers the
/// world-space bounds [lo, hi] seen from `towardLight` (near plane on the light's side), leaving
/// `marginTexels` of an n-texel map empty around them (closings then never reach the border).
Mat4 lightClipFromWorld(const Vec3d& towardLight, const Vec3d& lo, const Vec3d& hi, int n = 2048, int marginTexels = 0);

}  // namespace volstyle::core

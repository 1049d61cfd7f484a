#pragma once
/// \file stylizer.h
/// The light-shaft stylizer's engine (SPEC §7, the GI paper Sec. 3–4): rasterizes the light's
/// shadow map (depth and object ids) and the camera's G-buffer (normal, distance, colour) with GL,
/// then per pixel the average visibility V̄ along the view ray (Eq. 2) and the frame
///   L = L_surf e^{−σt s} + ρ p E (1 − e^{−σt s}) V̄        (directional light).
/// for a directional light, with the in-scattering integral taken numerically for a spot; then
/// the transfer function. Per object, the scattering's map is closed, dilated along epipolar
/// lines (Eq. 3) and given noise holes (Eq. 4–5). GL-free header; GL thread only.

#include <memory>
#include <optional>

#include "core/gpu/gpu_device.h"
#include "core/image/image.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

class GpuVolume;
namespace gl {
class ReadbackRing;
}

/// Where a live frame goes instead of `StylizedFrame::frame` (issue #40): its display bytes
/// (display_pack.comp) in a slot of `ring`, which the caller reads on its own thread and releases.
struct DisplayReadback {
    gl::ReadbackRing* ring = nullptr;
    double exposure = 0;
};

/// A frame and its AOVs (SPEC §7 "Outputs"), all linear.
struct StylizedFrame {
    Image frame;              ///< RGBA, alpha 1
    Image scattering;         ///< L_scat before any transfer function (rgb)
    Image averageVisibility;  ///< V̄ ∈ [0, 1] in rgb
    Image linearDepth;        ///< s: distance to the first surface (or the camera's far), rgb
    Image shadowMap;          ///< the light's depth in [0, 1] (1: nothing), side shadow_map_size
    Image modifiedShadowMap;  ///< the same after the occluders' manipulations (what V̄ reads)
    /// With a DisplayReadback (and no anchored TF constraints, which are applied on the CPU): the
    /// frame as display bytes — R, G, B, 255 per pixel, rows top to bottom, as a PNG of `frame`
    /// shows them — in slot `displaySlot` of the ring, which the caller releases; `frame` is then
    /// empty. Null otherwise: `frame` holds the picture.
    const uint8_t* displayBytes = nullptr;
    int displaySlot = -1;
    int pickedOccluder = -1;  ///< StylizeSettings::pick: the index of the occluder seen there, −1: none
    /// The transfer function the frame used, its anchored constraints moved to where they are
    /// now and compiled (empty without a TF).
    std::optional<TransferFunction> transferFunction;
    double shadowMs = 0;   ///< the shadow maps and the manipulations
    double mipmapMs = 0;   ///< the min-max mipmap (accelerated method)
    double gbufferMs = 0;
    double shadeMs = 0;     ///< the per-pixel pass: V̄, scattering, surfaces, transfer function
    double readbackMs = 0;  ///< the frame, its AOVs and the maps back to the CPU
    double totalMs = 0;
    /// The mipmap's and the per-pixel pass's GPU time alone (GL timer queries): on a GPU the wall
    /// clock above also counts the driver's latency and the clock's ramp, which a 1 ms pass drowns in.
    double mipmapGpuMs = 0, shadeGpuMs = 0;

    const Image& output(StylizerOutput which) const {
        switch (which) {
            case StylizerOutput::AverageVisibility: return averageVisibility;
            case StylizerOutput::LinearDepth: return linearDepth;
            case StylizerOutput::ShadowMap: return shadowMap;
            case StylizerOutput::ModifiedShadowMap: return modifiedShadowMap;
            case StylizerOutput::Scattering: return scattering;
            case StylizerOutput::Frame: break;
        }
        return frame;
    }
};

class Stylizer {
public:
    explicit Stylizer(GpuDevice& device);
    ~Stylizer();
    Stylizer(const Stylizer&) = delete;
    Stylizer& operator=(const Stylizer&) = delete;

    /// Renders `scene` (validated first; InvalidArgument names the problem) from its camera (on a
    /// path: sceneAtTime() places it). A TF of layers is compiled first; on a path the TFs of the
    /// keys around the scene's time are blended; with constraints anchored in the scene the frame
    /// is rendered without the TF, the anchors are found in its AOVs and the TF applied on the CPU.
    /// `medium`: the volume whose extinction is the scene's heterogeneous medium (`scene.volume`;
    /// the server passes the session's own GPU copy, never a second one); required with it.
    /// `display`: the frame comes back as display bytes in a read-back slot (a live stream).
    StylizedFrame render(const StylizerScene& scene, const StylizeSettings& settings = {}, GpuVolume* medium = nullptr,
                         const DisplayReadback* display = nullptr);

    /// About how many shadow-map lookups (or texel operations) a frame costs: the per-pixel pass
    /// and each manipulated occluder's edits (a dilation costs its kernel per texel). For a
    /// server's budget check before a frame holds the GL thread; CPU only.
    static double estimatedLookups(const StylizerScene& scene, const StylizeSettings& settings);
    /// What an accelerated ray costs in lookups (p99 of the min-max walk's iterations at 2048², with margin).
    static constexpr double kAcceleratedLookupsPerRay = 300;

    /// This device's speed in estimatedLookups() per second, measured: builtin:forest at 320×180
    /// with the naive V̄ (256 lookups a ray), rendered once to compile its kernels and then timed
    /// twice (the faster counts). A frame's fixed costs (shadow maps, G-buffer) are in the time,
    /// so small frames are not underestimated. About 0.5 s on llvmpipe, milliseconds on a GPU.
    double measureLookupsPerSecond();

private:
    StylizedFrame renderPass(const StylizerScene& scene, const StylizeSettings& settings, GpuVolume* medium,
                             const DisplayReadback* display = nullptr);
    GpuDevice& m_device;
};

}  // namespace volstyle::core

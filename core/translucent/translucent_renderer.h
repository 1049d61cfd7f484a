#pragma once
/// \file translucent_renderer.h
/// The translucent preview (SPEC §9; Kniss et al. 2003, Sec. 3): half-angle slicing. The volume's
/// bounding box is cut by planes orthogonal to the axis halfway between the light's travel and the
/// view direction (or its reverse, when they face each other); each slice is rasterized into the
/// eye buffer, lit by the light buffers, and then into the next light buffers, which carry the
/// direct light's transmittance and the forward-scattered indirect light to the next slice (Fig. 3,
/// Eq. 10–12). Light comes from the lighting's first directional light. GL thread only.

#include <memory>

#include "core/base/work_budget.h"
#include "core/gpu/gpu_device.h"
#include "core/image/image.h"
#include "core/render/gpu_volume.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/translucent/translucent_settings.h"

namespace volstyle::core {

struct TranslucentStats {
    int slices = 0;
    double totalMs = 0;
};

class TranslucentRenderer {
public:
    explicit TranslucentRenderer(GpuDevice& device);
    ~TranslucentRenderer();

    /// The picture: RGB radiance over the lighting's background (colour, map, lobes or plate),
    /// alpha the medium's opacity; `medium`, if given, gets the medium alone (premultiplied, no
    /// background: for compositing). `budget` is checked between slices. Throws InvalidArgument on
    /// a bad camera, lighting or settings.
    Image render(GpuVolume& volume, const Camera& camera, const Lighting& lighting, const TranslucentSettings& settings,
                 TranslucentStats* stats = nullptr, Image* medium = nullptr, const WorkBudget& budget = WorkBudget());

    /// An upper bound on the texels a render fills: every slice covering the whole image and the
    /// whole light buffer (the slices are the box's diagonal over the spacing, in voxels). With a
    /// measured rate it keeps a render that cannot finish within a budget from starting.
    static double estimatedTexels(Int3 dims, const Camera& camera, const TranslucentSettings& settings);

private:
    GpuDevice& m_device;
    struct Targets;
    std::unique_ptr<Targets> m_targets;
};

}  // namespace volstyle::core

#pragma once
/// \file stylizer_passes.h
/// The stylizer's frame as named steps (the GI paper Sec. 3–4, SPEC §7), internal to core/stylize:
///   1. shadowMaps   — the light's unmodified shadow map (depth and object ids), for surfaces;
///   2. shadowEdits  — the scattering's map: the objects left alone, then each manipulated one drawn
///                     alone, closed, dilated, holed and folded in by minimum (Sec. 4);
///   3. minMax       — the accelerated V̄'s min-max mipmap after the map in its buffer;
///   4. gBuffer      — the camera's normal and distance, colour and object id;
///   5. shade        — per pixel: V̄, the scattering and the frame (stylize.comp);
///   6. readBack     — the frame, and the AOVs and maps asked for.
/// Their render targets are made once per size and kept in the device's cache (StylizerTargets);
/// the occluders' meshes are uploaded once and kept there too, while the mesh lives.

#include <functional>
#include <memory>
#include <vector>

#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/gpu/gpu_device.h"
#include "core/shaders/layout.h"
#include "core/stylize/light_map.h"
#include "core/stylize/scene.h"
#include "core/stylize/stylizer.h"

namespace volstyle::core::stylize {

/// An occluder's mesh on the GPU: interleaved position + normal, 32-bit indices.
struct GpuMesh {
    explicit GpuMesh(const Mesh& m);
    gl::Buffer vertices, indices;
    gl::VertexArray vao;
    GLsizei indexCount = 0;
};

/// The GPU copy of `mesh`, from the device's cache (uploaded on first use; dropped with the mesh).
std::shared_ptr<const GpuMesh> gpuMesh(GpuDevice& device, const std::shared_ptr<const Mesh>& mesh);

/// A frame's render targets: the n×n shadow maps and the scattering map's buffer (with room for
/// the min-max levels when accelerated), the w×h G-buffer and the frame's output buffers.
struct StylizerTargets {
    StylizerTargets(int n, int width, int height, bool accelerated);
    size_t bytes() const { return m_bytes; }

    int n = 0, width = 0, height = 0;
    size_t mapBytes = 0, pixelBytes = 0;  ///< one n×n float map; one w×h RGBA float plane
    gl::Texture shadowDepth, shadowIds, scratchDepth;
    gl::Framebuffer shadowFb, scratchFb;  ///< depth + ids; depth only (an object drawn alone)
    gl::Buffer scatterDepth;               ///< the scattering's map (+ min-max levels)
    mutable gl::Buffer part;               ///< one object's map while it is edited (the edits take it by reference)
    gl::Texture surface, colour, depth;
    gl::Framebuffer gbufferFb;
    gl::Buffer pixels, layers;             ///< the frame; the AOV planes (layout::kStylizeLayers)

private:
    size_t m_bytes = 0;
};

/// The targets for this frame's sizes: the cached ones, else new ones (cached when they are at
/// most `keptBytes`: a one-off large frame's go back when it is done).
std::shared_ptr<const StylizerTargets> targetsFor(GpuDevice& device, int n, int width, int height, bool accelerated, size_t keptBytes);

/// What the steps of one frame share.
struct Frame {
    GpuDevice& device;
    const StylizerScene& scene;
    const StylizeSettings& settings;
    const LightMap map;
    const StylizerTargets& targets;
    std::vector<std::shared_ptr<const GpuMesh>> meshes;
    layout::StylizeParams p;
};

/// The parameters every pass reads (camera, light, medium, background, visibility method).
layout::StylizeParams frameParams(const StylizerScene& scene, const StylizeSettings& settings, const LightMap& map);

/// The steps, in order (see the file's comment); each adds its time to `out`.
void shadowMaps(Frame& f);
/// `threshold(m)`: the hole noise's threshold for a manipulation's probability (calibrated once).
void shadowEdits(Frame& f, const std::function<float(const Manipulation&)>& threshold, StylizedFrame& out);
void minMax(Frame& f, StylizedFrame& out);
void gBuffer(Frame& f, StylizedFrame& out);
/// `bindMedium(p)` binds the heterogeneous medium's textures (or placeholders) and fills its fields.
void shade(Frame& f, const std::function<void(layout::StylizeParams&)>& bindMedium, StylizedFrame& out);
void readBack(Frame& f, StylizedFrame& out);
/// The frame as display bytes in a slot of `display.ring` (display_pack.comp), fenced and waited
/// for: StylizedFrame::displayBytes and displaySlot; then the AOVs and maps `f.settings` asks for.
void readBackDisplay(Frame& f, const DisplayReadback& display, StylizedFrame& out);

}  // namespace volstyle::core::stylize

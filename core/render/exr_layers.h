#pragma once
/// \file exr_layers.h
/// How a render is laid out in an EXR for compositing (issue #10; docs/FORMATS.md): the main
/// RGBA is the medium alone, premultiplied, with no background (so `over` a plate adds the plate
/// once); the layers `background`, `emission`, `scattering` and `transmittance` follow, named
/// layer.R/G/B as Nuke and Blender read them.

#include <vector>

#include "core/image/image_io.h"
#include "core/render/renderer.h"

namespace volstyle::core {

/// The layers of `render`, pointing into it (keep it alive while they are used).
std::vector<ExrLayer> exrLayersOf(const RenderLayers& render);

}  // namespace volstyle::core

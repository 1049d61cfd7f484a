#include "core/render/exr_layers.h"

namespace volstyle::core {

std::vector<ExrLayer> exrLayersOf(const RenderLayers& render) {
    return {{"", &render.medium},
            {"background", &render.background},
            {"emission", &render.emission},
            {"scattering", &render.scattering},
            {"transmittance", &render.transmittance}};
}

}  // namespace volstyle::core

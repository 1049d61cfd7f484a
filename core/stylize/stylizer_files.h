#pragma once
/// \file stylizer_files.h
/// How a stylizer output is written (the CLI's -o and the API's frames share it).

#include "core/image/image_io.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

/// The frame and the scattering as pictures (sRGB, `exposure` stops in 8-bit files), V̄ and the
/// depths as data (linear, exposure ignored); EXR in float, so bright scattering and far depths
/// stay finite.
inline SaveOptions stylizerSaveOptions(StylizerOutput output, double exposure) {
    SaveOptions save;
    save.data = !isPicture(output);
    save.exposure = save.data ? 0 : exposure;
    save.halfFloat = false;
    return save;
}

}  // namespace volstyle::core

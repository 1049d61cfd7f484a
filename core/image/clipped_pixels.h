#pragma once
/// \file clipped_pixels.h
/// Targets painted over 8- or 16-bit images (issue #37): where the picture under the paint was
/// already at the format's maximum in a channel, the painted value says only "at least this
/// bright", not what the pixel should be. A solve fitting it would chase clipped values (and the
/// reach report blamed the unknowns). Clip-aware loading gives those pixels weight 0.

#include <cstddef>

#include "core/image/image.h"

namespace volstyle::core {

/// Sets the weight (alpha) of every pixel at 1 in all three channels (white: the format's maximum,
/// linear) to 0 and returns how many there were. Only white: a painted colour may well have one
/// channel at 255 (the page's orange brush is 255, 138, 61) and means what it shows, while an
/// overexposed picture is white; painting pure white over an 8-bit picture is read as clipped.
/// Only for targets decoded from an integer format: a float (EXR/HDR) target's values above 1 are values.
size_t ignoreClippedPixels(Image& target);

}  // namespace volstyle::core

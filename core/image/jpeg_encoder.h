#pragma once
/// \file jpeg_encoder.h
/// Live frames as JPEG in memory (issue #40): libjpeg-turbo's TurboJPEG API straight from the
/// frame's pixels, with no temporary file (encodeImage's OpenImageIO path writes one). The pixels
/// are shown as a PNG shows them: linear RGB × 2^exposure, clamped to [0, 1], sRGB-encoded
/// (through a table), 8 bits; alpha is dropped.

#include <cstdint>
#include <string>
#include <vector>

#include "core/image/image.h"

namespace volstyle::core {

/// The image's display bytes, RGB, rows top to bottom (as saveImage writes a PNG, to ±1 level).
std::vector<uint8_t> displayBytes(const Image& image, double exposure = 0);

/// A baseline JPEG of the image at `quality` (1–100), full-resolution chroma (4:4:4: a stylized
/// frame's coloured shafts and foliage edges lost 11 dB of PSNR to 4:2:0 at quality 85).
/// Throws InvalidArgument for an empty image or a quality out of range, IoError if the encoder fails.
std::string encodeJpeg(const Image& image, int quality = 85, double exposure = 0);

/// The same from display bytes already made (a live frame's, display_pack.comp): R, G, B and a
/// byte that is ignored per pixel, rows top to bottom, `width` × `height`.
std::string encodeJpegRgbx(const uint8_t* rgbx, int width, int height, int quality = 85);

}  // namespace volstyle::core

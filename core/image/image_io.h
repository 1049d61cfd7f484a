#pragma once
/// \file image_io.h
/// Image files through OpenImageIO (kept inside image_io.cpp). 8/16-bit formats (PNG, JPEG,
/// TIFF) are sRGB: linearised on load, encoded on save. Float formats (EXR, HDR, float TIFF) are
/// linear. Alpha, when present, is kept (as a weight for targets).

#include <functional>
#include <string>
#include <vector>

#include "core/image/image.h"

namespace volstyle::core {

struct LoadedImage {
    Image image;
    bool hasAlpha = false;
    int channels = 0;
    bool wasSrgb = false;  ///< the file was 8/16-bit and was linearised
    /// A volstyle render's EXR (docs/FORMATS.md): its `background` and `transmittance` layers
    /// (RGB; empty for any other file). `image` is then the medium alone, premultiplied.
    Image background, transmittance;
    bool isRender() const { return !background.empty() && !transmittance.empty(); }
};

/// Called with an image's size once its header is read and before any pixel is decoded: it may
/// throw to refuse the image (an upload of the wrong size never costs its decode).
using ImageHeaderCheck = std::function<void(int width, int height)>;

/// Loads an image file. Throws IoError (missing, corrupt or truncated file) or InvalidArgument
/// (non-finite values, more than `maxSide` pixels on a side).
LoadedImage loadImage(const std::string& path, int maxSide = 8192, const ImageHeaderCheck& checkHeader = {});

/// Loads an image from bytes in memory (an upload); `nameHint` is used in error messages.
LoadedImage loadImageFromMemory(const void* data, size_t size, const std::string& nameHint,
                                int maxSide = 8192, const ImageHeaderCheck& checkHeader = {});

/// The picture an image shows, as a solve's target reads it: a volstyle render's EXR is its medium
/// over its background, RGB + transmittance × background, with weight (alpha) 1 — its alpha is
/// coverage, not paint (issue #34: read as the medium alone, an absorber's views were black); any
/// other image is itself.
Image pictureOf(const LoadedImage& loaded);

struct SaveOptions {
    double exposure = 0;        ///< stops; applied as 2^exposure before encoding
    bool writeAlpha = false;    ///< PNG/TIFF: keep alpha (EXR always has it)
    bool halfFloat = true;      ///< EXR: half instead of float
    int bits = 8;               ///< PNG/TIFF: 8 or 16
    /// Data, not a picture (V̄, depths): 8/16-bit files store the values linearly, clamped to
    /// [0, 1], without the sRGB curve (set exposure to 0 for the values as they are).
    bool data = false;
};

/// Saves by extension (.png .jpg .jpeg .tif .tiff .exr .hdr). Throws IoError / InvalidArgument.
void saveImage(const std::string& path, const Image& image, const SaveOptions& options = {});

/// One part of a layered EXR. The layer named "" is the main image, channels R, G, B, A; the
/// others are written as NAME.R, NAME.G, NAME.B (the layer.channel names Nuke shows as layers and
/// Blender's Image node as passes).
struct ExrLayer {
    std::string name;
    const Image* image = nullptr;
};

/// Writes one EXR holding every layer (the same size), half float unless `halfFloat` is false.
void saveExrLayers(const std::string& path, const std::vector<ExrLayer>& layers, bool halfFloat = true);
std::string encodeExrLayers(const std::vector<ExrLayer>& layers, bool halfFloat = true);

/// Encodes to PNG, JPEG or EXR bytes in memory (for HTTP answers): `format` is "png", "jpeg" or "exr".
std::string encodeImage(const Image& image, const std::string& format,
                        const SaveOptions& options = {});

}  // namespace volstyle::core

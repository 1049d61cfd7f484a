#include "core/image/jpeg_encoder.h"

#include <turbojpeg.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

/// sRGB bytes of linear values in [0, 1] at kSteps + 1 points: the curve's steepest slope (12.92
/// near black) moves a byte by at most 12.92 · 255 / kSteps = 0.2 levels between entries.
constexpr int kSteps = 1 << 14;

const std::array<uint8_t, kSteps + 1>& srgbTable() {
    static const auto table = [] {
        std::array<uint8_t, kSteps + 1> t{};
        for (int i = 0; i <= kSteps; ++i) t[size_t(i)] = uint8_t(std::lround(255.0f * linearToSrgb(float(i) / kSteps)));
        return t;
    }();
    return table;
}

}  // namespace

std::vector<uint8_t> displayBytes(const Image& image, double exposure) {
    if (image.empty()) throw InvalidArgument("the image is empty");
    const auto& table = srgbTable();
    const float scale = float(std::exp2(exposure)) * kSteps;
    std::vector<uint8_t> rgb(image.pixelCount() * 3);
    for (size_t i = 0; i < image.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            const float v = image.rgba[4 * i + size_t(c)] * scale;
            rgb[3 * i + size_t(c)] = table[size_t(v > 0 ? std::min(v + 0.5f, float(kSteps)) : 0)];  // NaN reads black
        }
    return rgb;
}

namespace {

/// Baseline, 4:4:4, the fast DCT; `format` a TJPF_* pixel layout of `pixels`.
std::string compress(const uint8_t* pixels, int width, int height, int format, int quality) {
    if (quality < 1 || quality > 100) throw InvalidArgument("JPEG quality must be 1–100, got " + std::to_string(quality));
    if (width <= 0 || height <= 0) throw InvalidArgument("the image is empty");
    // One compressor per thread: tjInitCompress allocates, and frames come one after another.
    thread_local std::unique_ptr<void, int (*)(tjhandle)> compressor(tjInitCompress(), tjDestroy);
    if (!compressor) throw IoError("libjpeg-turbo: no compressor");
    unsigned char* out = nullptr;
    unsigned long size = 0;
    if (tjCompress2(compressor.get(), pixels, width, 0, height, format, &out, &size, TJSAMP_444, quality, TJFLAG_FASTDCT) != 0) {
        const std::string why = tjGetErrorStr2(compressor.get());
        tjFree(out);
        throw IoError("libjpeg-turbo could not encode the frame: " + why);
    }
    std::string bytes(reinterpret_cast<const char*>(out), size);
    tjFree(out);
    return bytes;
}

}  // namespace

std::string encodeJpeg(const Image& image, int quality, double exposure) {
    const std::vector<uint8_t> rgb = displayBytes(image, exposure);
    return compress(rgb.data(), image.width, image.height, TJPF_RGB, quality);
}

std::string encodeJpegRgbx(const uint8_t* rgbx, int width, int height, int quality) {
    return compress(rgbx, width, height, TJPF_RGBX, quality);
}

}  // namespace volstyle::core

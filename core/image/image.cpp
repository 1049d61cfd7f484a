#include "core/image/image.h"

#include <cmath>

namespace volstyle::core {

size_t Image::countNonFinite() const {
    size_t n = 0;
    for (float v : rgba) n += std::isfinite(v) ? 0 : 1;
    return n;
}

float srgbToLinear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float v) {
    return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

}  // namespace volstyle::core

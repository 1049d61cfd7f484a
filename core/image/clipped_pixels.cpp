#include "core/image/clipped_pixels.h"

namespace volstyle::core {

size_t ignoreClippedPixels(Image& target) {
    // The top code value (255, 65535) decodes to exactly 1 in linear; a hair below covers the
    // float rounding of the sRGB curve.
    constexpr float kClipped = 1.0f - 1e-6f;
    size_t clipped = 0;
    for (size_t i = 0; i < target.pixelCount(); ++i) {
        float* p = &target.rgba[4 * i];
        if (p[0] >= kClipped && p[1] >= kClipped && p[2] >= kClipped && p[3] > 0) {
            p[3] = 0;
            ++clipped;
        }
    }
    return clipped;
}

}  // namespace volstyle::core

#pragma once
// Comparing images in tests.
#include <algorithm>
#include <cmath>

#include "core/image/image.h"

namespace volstyle::test {

/// The largest absolute difference of any channel of any pixel (same-sized images).
inline double maxAbsDifference(const core::Image& a, const core::Image& b) {
    double m = 0;
    for (size_t i = 0; i < a.rgba.size(); ++i) m = std::max(m, double(std::abs(a.rgba[i] - b.rgba[i])));
    return m;
}

/// The RMS difference over the RGB channels of every pixel (same-sized images).
inline double rmsDifference(const core::Image& a, const core::Image& b) {
    double s = 0;
    for (size_t i = 0; i < a.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) s += std::pow(double(a.rgba[4 * i + size_t(c)]) - b.rgba[4 * i + size_t(c)], 2);
    return std::sqrt(s / (3.0 * double(a.pixelCount())));
}

}  // namespace volstyle::test

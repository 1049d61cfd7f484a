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

}  // namespace volstyle::test

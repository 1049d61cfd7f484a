#pragma once
// Small helpers shared by the benchmarks: medians, error measures and JSON-lines output.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"

namespace volstyle::bench {

/// `count` cameras of w×h on an orbit of radius 3 around the unit volume (bench/solver's views).
inline std::vector<core::Camera> orbitCameras(int count, int w, int h) {
    std::vector<core::Camera> cams;
    for (int i = 0; i < count; ++i) {
        const double a = 0.3 + 2 * std::numbers::pi * i / count;
        core::Camera c;
        c.eye = {3.0 * std::sin(a), 0.4 * std::cos(3 * a) + 0.013, 3.0 * std::cos(a)};
        c.target = {0.011, -0.07, 0.013};
        c.fovYDeg = 42;
        c.width = w, c.height = h;
        cams.push_back(c);
    }
    return cams;
}

inline double mean(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x / double(v.size());
    return s;
}

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    size_t n = v.size();
    return n == 0 ? 0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

/// max over pixels and RGB of |a − b| / (|b| + floor·peak(b)): relative error with a floor for
/// pixels near zero.
inline double maxRelativeError(const core::Image& a, const core::Image& b, double floor = 1e-3) {
    float peak = 0;
    for (size_t i = 0; i < b.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) peak = std::max(peak, std::abs(b.rgba[4 * i + c]));
    double worst = 0;
    for (size_t i = 0; i < b.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            double x = a.rgba[4 * i + c], y = b.rgba[4 * i + c];
            worst = std::max(worst, std::abs(x - y) / (std::abs(y) + floor * peak));
        }
    return worst;
}

/// Root-mean-square difference over RGB divided by the RMS of `b`.
inline double relativeRms(const core::Image& a, const core::Image& b) {
    double num = 0, den = 0;
    for (size_t i = 0; i < b.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            double d = double(a.rgba[4 * i + c]) - b.rgba[4 * i + c];
            num += d * d;
            den += double(b.rgba[4 * i + c]) * b.rgba[4 * i + c];
        }
    return den > 0 ? std::sqrt(num / den) : 0;
}

}  // namespace volstyle::bench

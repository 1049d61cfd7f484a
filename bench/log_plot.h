#pragma once
// A minimal log–log plot for the benchmarks' time-against-error figures (no fonts: the docs say
// which colour is which): decade grid lines, each series a coloured polyline with square markers.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/image/image.h"
#include "core/math/vec.h"

namespace volstyle::bench {

/// A minimal log–log plot: series as coloured polylines with square markers.
struct LogPlot {
    core::Image img{640, 420};
    double x0, x1, y0, y1;  // log10 ranges
    LogPlot(double xmin, double xmax, double ymin, double ymax)
        : x0(std::floor(std::log10(xmin))), x1(std::ceil(std::log10(xmax))), y0(std::floor(std::log10(ymin))), y1(std::ceil(std::log10(ymax))) {
        for (size_t i = 0; i < img.pixelCount(); ++i) img.rgba[4 * i] = img.rgba[4 * i + 1] = img.rgba[4 * i + 2] = img.rgba[4 * i + 3] = 1;
        for (double d = x0; d <= x1; d += 1) line(std::pow(10, d), std::pow(10, y0), std::pow(10, d), std::pow(10, y1), {0.8f, 0.8f, 0.8f});
        for (double d = y0; d <= y1; d += 1) line(std::pow(10, x0), std::pow(10, d), std::pow(10, x1), std::pow(10, d), {0.8f, 0.8f, 0.8f});
    }
    std::pair<double, double> px(double x, double y) const {
        return {40 + (std::log10(x) - x0) / (x1 - x0) * 580, 400 - (std::log10(y) - y0) / (y1 - y0) * 380};
    }
    void dot(int x, int y, Vec3 c) {
        if (x >= 0 && y >= 0 && x < img.width && y < img.height) {
            float* p = img.pixel(x, y);
            p[0] = c.x, p[1] = c.y, p[2] = c.z;
        }
    }
    void line(double ax, double ay, double bx, double by, Vec3 c) {
        auto [x0p, y0p] = px(ax, ay);
        auto [x1p, y1p] = px(bx, by);
        int n = int(std::max(std::abs(x1p - x0p), std::abs(y1p - y0p))) + 1;
        for (int i = 0; i <= n; ++i) dot(int(x0p + (x1p - x0p) * i / n), int(y0p + (y1p - y0p) * i / n), c);
    }
    void series(const std::vector<std::pair<double, double>>& pts, Vec3 c) {
        for (size_t i = 0; i < pts.size(); ++i) {
            if (!(pts[i].first > 0 && pts[i].second > 0)) continue;
            auto [x, y] = px(pts[i].first, pts[i].second);
            for (int dy = -3; dy <= 3; ++dy)
                for (int dx = -3; dx <= 3; ++dx) dot(int(x) + dx, int(y) + dy, c);
            if (i > 0 && pts[i - 1].first > 0 && pts[i - 1].second > 0) line(pts[i - 1].first, pts[i - 1].second, pts[i].first, pts[i].second, c);
        }
    }
};


}  // namespace volstyle::bench

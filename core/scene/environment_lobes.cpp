#include "core/scene/environment_lobes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

constexpr double kPi = std::numbers::pi;

/// The solid angle of texel row y of an h-row lat-long map, per texel of a w-wide row:
/// (2π/w)·(cos θ0 − cos θ1), exact for the band.
double texelSolidAngle(int y, int w, int h) {
    const double t0 = kPi * y / h, t1 = kPi * (y + 1) / h;
    return 2 * kPi / w * (std::cos(t0) - std::cos(t1));
}

/// Each lobe's cell measured on a kProjectionWidth-wide lat-long grid: the solid angles of the
/// texels whose centres it holds (so they sum to 4π, or 2π over the upper hemisphere), computed
/// once per basis.
std::vector<double> measureCells(const LobeBasis& basis) {
    static std::mutex mutex;
    static std::map<std::string, std::vector<double>> measured;
    std::lock_guard lock(mutex);
    auto [it, fresh] = measured.try_emplace(basis.key());
    if (!fresh) return it->second;
    const int w = kProjectionWidth, h = w / 2;
    std::vector<double> omega(basis.directions.size(), 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int cell = basis.cellOf(latLongDirection((x + 0.5) / w, (y + 0.5) / h));
            if (cell >= 0) omega[size_t(cell)] += texelSolidAngle(y, w, h);
        }
    return it->second = omega;
}

}  // namespace

LobeBasis LobeBasis::make(int count, LobeDomain domain) {
    if (count < kMinLobes || count > kMaxLobes)
        throw InvalidArgument("lobes: " + std::to_string(count) + " is outside [" + std::to_string(kMinLobes) + ", " + std::to_string(kMaxLobes) + "]");
    LobeBasis b;
    b.domain = domain;
    // Fibonacci lattice: equal-area bands in y (the sphere's area is uniform in y), successive
    // points a golden angle apart in azimuth.
    const double golden = kPi * (3 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double y = domain == LobeDomain::Sphere ? 1 - (2 * i + 1.0) / count : 1 - (i + 0.5) / count;
        const double r = std::sqrt(std::max(0.0, 1 - y * y)), phi = golden * i;
        b.directions.push_back({r * std::sin(phi), y, -r * std::cos(phi)});
    }
    return b;
}

std::vector<double> LobeBasis::solidAngles() const { return measureCells(*this); }

int LobeBasis::cellOf(const Vec3d& direction) const {
    if (domain == LobeDomain::UpperHemisphere && direction.y < 0) return -1;
    int best = -1;
    double bestDot = -2;
    for (int i = 0; i < size(); ++i) {
        const double d = dot(directions[size_t(i)], direction);
        if (d > bestDot) bestDot = d, best = i;
    }
    return best;
}

std::vector<std::vector<int>> LobeBasis::neighbours(int k) const {
    std::vector<std::vector<int>> out(directions.size());
    for (int i = 0; i < size(); ++i) {
        std::vector<std::pair<double, int>> byAngle;
        for (int j = 0; j < size(); ++j)
            if (j != i) byAngle.push_back({-dot(directions[size_t(i)], directions[size_t(j)]), j});
        const int m = std::min(k, int(byAngle.size()));
        std::partial_sort(byAngle.begin(), byAngle.begin() + m, byAngle.end());
        for (int j = 0; j < m; ++j) out[size_t(i)].push_back(byAngle[size_t(j)].second);
    }
    return out;
}

std::string LobeBasis::key() const {
    return "lobes:" + std::to_string(size()) + (domain == LobeDomain::Sphere ? ":sphere" : ":upper_hemisphere");
}

Int3 lobeGridDims(Int3 volumeDims, int resolution) {
    const int longest = std::max({volumeDims.x, volumeDims.y, volumeDims.z});
    if (longest <= resolution) return volumeDims;
    const double scale = double(resolution) / longest;
    auto axis = [&](int n) { return std::max(2, int(std::lround(n * scale))); };
    return {axis(volumeDims.x), axis(volumeDims.y), axis(volumeDims.z)};
}

Vec3d latLongDirection(double u, double v) {
    const double phi = (u - 0.5) * 2 * kPi, theta = v * kPi;
    return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

void latLongCoordinates(const Vec3d& direction, double& u, double& v) {
    u = 0.5 + std::atan2(direction.x, -direction.z) / (2 * kPi);
    v = std::atan2(std::hypot(direction.x, direction.z), direction.y) / kPi;
}

Vec3d sampleLatLong(const Image& map, const Vec3d& direction) {
    double u, v;
    latLongCoordinates(direction, u, v);
    const double x = u * map.width - 0.5, y = v * map.height - 0.5;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    auto texel = [&](int xi, int yi) {
        xi = ((xi % map.width) + map.width) % map.width;
        yi = std::clamp(yi, 0, map.height - 1);
        const float* p = map.pixel(xi, yi);
        return Vec3d(p[0], p[1], p[2]);
    };
    return (texel(x0, y0) * (1 - fx) + texel(x0 + 1, y0) * fx) * (1 - fy) +
           (texel(x0, y0 + 1) * (1 - fx) + texel(x0 + 1, y0 + 1) * fx) * fy;
}

std::vector<Vec3d> projectEnvironment(const LobeBasis& basis, const Image& map) {
    if (map.empty()) throw InvalidArgument("environment: the map is empty");
    // Blocks of the map, each the solid-angle weighted mean of its texels, at most
    // kProjectionWidth × kProjectionWidth/2 of them; a map that small is its own blocks.
    const int bw = std::min(map.width, kProjectionWidth), bh = std::min(map.height, kProjectionWidth / 2);
    std::vector<Vec3d> sum(basis.directions.size());
    std::vector<double> weight(basis.directions.size(), 0.0);
    for (int by = 0; by < bh; ++by) {
        const int y0 = int(int64_t(by) * map.height / bh), y1 = int(int64_t(by + 1) * map.height / bh);
        for (int bx = 0; bx < bw; ++bx) {
            const int x0 = int(int64_t(bx) * map.width / bw), x1 = int(int64_t(bx + 1) * map.width / bw);
            Vec3d radiance;
            double omega = 0;
            for (int y = y0; y < y1; ++y) {
                const double texelOmega = texelSolidAngle(y, map.width, map.height);
                for (int x = x0; x < x1; ++x) {
                    const float* p = map.pixel(x, y);
                    radiance += Vec3d(p[0], p[1], p[2]) * texelOmega;
                    omega += texelOmega;
                }
            }
            // The block's centre direction picks its cell (exact for a map no wider than the limit).
            const int cell = basis.cellOf(latLongDirection((x0 + x1) * 0.5 / map.width, (y0 + y1) * 0.5 / map.height));
            if (cell < 0) continue;
            sum[size_t(cell)] += radiance;
            weight[size_t(cell)] += omega;
        }
    }
    std::vector<Vec3d> out(basis.directions.size());
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = weight[i] > 0 ? sum[i] / weight[i] : sampleLatLong(map, basis.directions[i]);
    return out;
}

Image lobesToLatLong(const LobeBasis& basis, const std::vector<Vec3d>& radiance, int width, int height) {
    if (radiance.size() != basis.directions.size())
        throw InvalidArgument("environment: " + std::to_string(radiance.size()) + " radiances for " + std::to_string(basis.directions.size()) + " lobes");
    Image img(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const int cell = basis.cellOf(latLongDirection((x + 0.5) / width, (y + 0.5) / height));
            const Vec3d c = cell >= 0 ? radiance[size_t(cell)] : Vec3d();
            float* p = img.pixel(x, y);
            p[0] = float(c.x), p[1] = float(c.y), p[2] = float(c.z), p[3] = 1;
        }
    return img;
}

std::string latLongShapeProblem(const Image& latLong) {
    if (latLong.empty()) return "the map is empty";
    if (std::abs(latLong.width - 2 * latLong.height) > 1)
        return "a latitude-longitude map is twice as wide as high; this one is " + std::to_string(latLong.width) + "x" +
               std::to_string(latLong.height);
    return "";
}

std::string latLongMapProblem(const Image& latLong) {
    if (std::string shape = latLongShapeProblem(latLong); !shape.empty()) return shape;
    size_t nonFinite = 0, negative = 0;
    for (size_t i = 0; i < latLong.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            const float x = latLong.rgba[4 * i + size_t(c)];
            nonFinite += std::isfinite(x) ? 0 : 1;
            negative += x < 0 ? 1 : 0;
        }
    if (nonFinite) return "the map has " + std::to_string(nonFinite) + " non-finite (NaN/Inf) values";
    if (negative) return "the map has " + std::to_string(negative) + " negative values; radiance must be >= 0";
    return "";
}

}  // namespace volstyle::core

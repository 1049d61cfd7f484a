#include "core/render/curved_ray.h"

#include <algorithm>
#include <cmath>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

/// The system's right-hand side at state s: (dx/ds, dv/ds).
std::pair<Vec3d, Vec3d> derivative(const IndexField& f, const RayState& s) {
    return {s.v / f.n(s.x), f.gradient(s.x)};
}

RayState advance(const RayState& s, const std::pair<Vec3d, Vec3d>& d, double h) { return {s.x + d.first * h, s.v + d.second * h}; }

}  // namespace

RayState stepRay(const IndexField& f, const RayState& s, double h, RayScheme scheme) {
    const auto k1 = derivative(f, s);
    switch (scheme) {
        case RayScheme::EulerForward: return advance(s, k1, h);
        case RayScheme::Midpoint: return advance(s, derivative(f, advance(s, k1, h / 2)), h);
        case RayScheme::RungeKutta4: {
            const auto k2 = derivative(f, advance(s, k1, h / 2));
            const auto k3 = derivative(f, advance(s, k2, h / 2));
            const auto k4 = derivative(f, advance(s, k3, h));
            return {s.x + (k1.first + k2.first * 2.0 + k3.first * 2.0 + k4.first) * (h / 6),
                    s.v + (k1.second + k2.second * 2.0 + k3.second * 2.0 + k4.second) * (h / 6)};
        }
    }
    return s;
}

std::vector<RayState> traceRay(const IndexField& f, const Vec3d& origin, const Vec3d& direction, double h, double maxLength,
                               RayScheme scheme, const std::function<bool(const RayState&)>& done) {
    if (!(h > 0) || !(maxLength > 0)) throw InvalidArgument("traceRay: the step and the length must be positive");
    std::vector<RayState> path{{origin, normalize(direction) * f.n(origin)}};
    for (double s = 0; s < maxLength && !done(path.back()); s += h) path.push_back(stepRay(f, path.back(), std::min(h, maxLength - s), scheme));
    return path;
}

IndexField luneburgLens(double R) {
    return {[R](const Vec3d& x) {
                const double r2 = dot(x, x) / (R * R);
                return r2 < 1 ? std::sqrt(2 - r2) : 1.0;
            },
            [R](const Vec3d& x) {
                const double r2 = dot(x, x) / (R * R);
                return r2 < 1 ? x * (-1.0 / (R * R * std::sqrt(2 - r2))) : Vec3d(0, 0, 0);
            }};
}

IndexField smoothSphere(double R, double inside, double width) {
    // n(r) = 1 + (inside − 1)·S((R − r)/width + 1/2), S the smoothstep on [0, 1].
    auto step = [=](double r, double* slope) {
        const double t = std::clamp((R - r) / width + 0.5, 0.0, 1.0);
        if (slope) *slope = (t > 0 && t < 1) ? (inside - 1) * 6 * t * (1 - t) * (-1 / width) : 0.0;
        return 1 + (inside - 1) * t * t * (3 - 2 * t);
    };
    return {[=](const Vec3d& x) { return step(length(x), nullptr); },
            [=](const Vec3d& x) {
                const double r = length(x);
                double slope = 0;
                step(r, &slope);
                return r > 0 ? x * (slope / r) : Vec3d(0, 0, 0);
            }};
}

IndexField indexFieldOf(const Volume& volume) {
    if (!volume.refractiveIndex()) throw InvalidArgument("the volume has no refractive_index grid");
    // The volume outlives the field (documented): share its grid and layout without copying.
    return indexFieldOf(std::shared_ptr<const std::vector<float>>(std::shared_ptr<void>(), &*volume.refractiveIndex()), volume.dims(),
                        volume.worldFromIndex(), std::shared_ptr<const BrickLayout>(std::shared_ptr<void>(), volume.bricks()));
}

IndexField indexFieldOf(std::shared_ptr<const std::vector<float>> values, Int3 n, const Mat4& worldFromIndex,
                        std::shared_ptr<const BrickLayout> bricks) {
    const size_t stored = bricks ? bricks->storedVoxels() : size_t(n.volume());
    if (!values || values->size() != stored || (bricks && !(bricks->dims() == n)))
        throw InvalidArgument("indexFieldOf: the grid does not match its dims");
    const Mat4 indexFromWorld = worldFromIndex.inverseAffine();
    // n and its index-space gradient at index-space point p (inside the voxels' box).
    auto sample = [grid = std::move(values), bricks = std::move(bricks), n](const Vec3d& p, Vec3d* gradient) {
        int i0[3], i1[3];
        double f[3];
        bool clampedLow[3], clampedHigh[3];
        for (int a = 0; a < 3; ++a) {
            const double c = p[a];
            clampedLow[a] = c < 0, clampedHigh[a] = c > n[a] - 1;
            const double cc = std::clamp(c, 0.0, double(n[a] - 1));
            i0[a] = std::min(int(cc), n[a] - 1), i1[a] = std::min(i0[a] + 1, n[a] - 1), f[a] = cc - i0[a];
        }
        auto at = [&](int i, int j, int k) {
            return double((*grid)[bricks ? bricks->storageIndex({i, j, k}) : (size_t(k) * size_t(n.y) + size_t(j)) * size_t(n.x) + size_t(i)]);
        };
        double value = 0;
        Vec3d g(0, 0, 0);
        for (int c = 0; c < 8; ++c) {
            const int ii = c & 1 ? i1[0] : i0[0], jj = c & 2 ? i1[1] : i0[1], kk = c & 4 ? i1[2] : i0[2];
            const double wx = c & 1 ? f[0] : 1 - f[0], wy = c & 2 ? f[1] : 1 - f[1], wz = c & 4 ? f[2] : 1 - f[2];
            const double v = at(ii, jj, kk);
            value += wx * wy * wz * v;
            g.x += (c & 1 ? 1 : -1) * wy * wz * v;
            g.y += (c & 2 ? 1 : -1) * wx * wz * v;
            g.z += (c & 4 ? 1 : -1) * wx * wy * v;
        }
        for (int a = 0; a < 3; ++a)  // flat where clamped (and across a single voxel)
            if (clampedLow[a] || clampedHigh[a] || i0[a] == i1[a]) g[a] = 0;
        if (gradient) *gradient = g;
        return value;
    };
    auto inside = [n](const Vec3d& p) {
        for (int a = 0; a < 3; ++a)
            if (!(p[a] >= -0.5 && p[a] <= n[a] - 0.5)) return false;
        return true;
    };
    return {[=](const Vec3d& x) {
                const Vec3d p = indexFromWorld.applyPoint(x);
                return inside(p) ? sample(p, nullptr) : 1.0;
            },
            [=](const Vec3d& x) {
                const Vec3d p = indexFromWorld.applyPoint(x);
                if (!inside(p)) return Vec3d(0, 0, 0);
                Vec3d g;
                sample(p, &g);
                // ∂n/∂x_world = Σ_a ∂n/∂p_a · ∂p_a/∂x_world: the transpose of indexFromWorld's linear part.
                return Vec3d(indexFromWorld(0, 0) * g.x + indexFromWorld(1, 0) * g.y + indexFromWorld(2, 0) * g.z,
                             indexFromWorld(0, 1) * g.x + indexFromWorld(1, 1) * g.y + indexFromWorld(2, 1) * g.z,
                             indexFromWorld(0, 2) * g.x + indexFromWorld(1, 2) * g.y + indexFromWorld(2, 2) * g.z);
            }};
}

}  // namespace volstyle::core

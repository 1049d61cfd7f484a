#pragma once
/// \file march_ref.h
/// The pieces of the GL march (core/shaders/common/*.glsl) written plainly for the CPU oracles,
/// templated on precision: trilinear lookups clamped to the edge, the ray/box test, equal
/// segments sampled at midpoints, and the phase function.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/shaders/layout.h"

namespace volstyle::core::cpu_ref::detail {

template <typename S>
using V3 = Vec3T<S>;

/// Trilinear lookup of an RGB grid (any element type) at index-space p, clamped to the edge.
template <typename S, typename T>
V3<S> trilinear(const std::vector<T>& g, Int3 n, const V3<S>& p, int stride = 3) {
    S q[3];
    int i0[3], i1[3];
    S f[3];
    for (int a = 0; a < 3; ++a) {
        q[a] = std::clamp(p[a], S(0), S(n[a] - 1));
        i0[a] = std::min(int(std::floor(q[a])), n[a] - 1);
        i1[a] = std::min(i0[a] + 1, n[a] - 1);
        f[a] = q[a] - S(i0[a]);
    }
    V3<S> r(S(0));
    for (int c = 0; c < 8; ++c) {
        int x = (c & 1) ? i1[0] : i0[0], y = (c & 2) ? i1[1] : i0[1], z = (c & 4) ? i1[2] : i0[2];
        S w = ((c & 1) ? f[0] : 1 - f[0]) * ((c & 2) ? f[1] : 1 - f[1]) * ((c & 4) ? f[2] : 1 - f[2]);
        size_t idx = size_t(stride) * ((size_t(z) * n.y + size_t(y)) * n.x + size_t(x));
        r += V3<S>(S(g[idx]), S(g[idx + 1]), S(g[idx + 2])) * w;
    }
    return r;
}

/// [tEnter, tExit] of o + t d against the voxels' box [-0.5, n-0.5]³, grown by `margin` voxels.
template <typename S>
std::pair<S, S> intersectBox(const V3<S>& o, const V3<S>& d, Int3 n, S margin = S(0)) {
    S lo = -std::numeric_limits<S>::max(), hi = std::numeric_limits<S>::max();
    for (int a = 0; a < 3; ++a) {
        S inv = S(1) / (d[a] == 0 ? S(1e-30) : d[a]);
        S t0 = (S(-0.5) - margin - o[a]) * inv, t1 = (S(n[a]) - S(0.5) + margin - o[a]) * inv;
        lo = std::max(lo, std::min(t0, t1));
        hi = std::min(hi, std::max(t0, t1));
    }
    return {lo, hi};
}

/// Equal segments of at most `step` voxels over [t0, t1].
template <typename S>
struct Segments {
    S t0, dt;
    int count;
    Segments(S a, S b, const V3<S>& d, S step) {
        S voxels = (b - a) * length(d);
        count = std::max(1, int(std::ceil(voxels / step)));
        t0 = a;
        dt = (b - a) / S(count);
    }
    S mid(int i) const { return t0 + (S(i) + S(0.5)) * dt; }
};

/// occupancy.comp's bricks: the largest extinction (any channel) over each kBrickSize³ brick and a
/// one-voxel apron, which bounds every trilinear lookup within the brick.
struct BrickBound {
    Int3 bricks;
    std::vector<float> bound;

    BrickBound(const std::vector<float>& extinction, Int3 n) {
        const int b = layout::kBrickSize;
        bricks = {(n.x + b - 1) / b, (n.y + b - 1) / b, (n.z + b - 1) / b};
        bound.assign(size_t(bricks.volume()), 0.0f);
        for (int z = 0; z < n.z; ++z)
            for (int y = 0; y < n.y; ++y)
                for (int x = 0; x < n.x; ++x) {
                    const size_t v = 3 * ((size_t(z) * n.y + size_t(y)) * n.x + size_t(x));
                    const float m = std::max({extinction[v], extinction[v + 1], extinction[v + 2]});
                    // Every brick whose box grown by a voxel holds voxel (x, y, z).
                    for (int k = std::max(0, (z - 1) / b); k <= std::min(bricks.z - 1, (z + 1) / b); ++k)
                        for (int j = std::max(0, (y - 1) / b); j <= std::min(bricks.y - 1, (y + 1) / b); ++j)
                            for (int i = std::max(0, (x - 1) / b); i <= std::min(bricks.x - 1, (x + 1) / b); ++i) {
                                float& slot = bound[(size_t(k) * bricks.y + size_t(j)) * bricks.x + size_t(i)];
                                slot = std::max(slot, m);
                            }
                }
    }

    /// The bound of the brick holding index-space point p (march_segments.glsl's brickAt).
    template <typename S>
    S at(const V3<S>& p) const {
        int c[3];
        for (int a = 0; a < 3; ++a)
            c[a] = std::clamp(int(std::floor((p[a] + S(0.5)) / S(layout::kBrickSize))), 0, bricks[a] - 1);
        return S(bound[(size_t(c[2]) * bricks.y + size_t(c[1])) * bricks.x + size_t(c[0])]);
    }
};

/// Calls visit(tMid, dt) for segment s of `seg` on the ray o + t d, cut as march.glsl's splitDense
/// cuts it: into sub-segments of at most kMarchDenseSegmentDepth where its brick is dense.
template <typename S, typename Visit>
void forEachSubsegment(const Segments<S>& seg, int s, const V3<S>& o, const V3<S>& d, const BrickBound& bricks, Visit&& visit) {
    const S tMid = seg.mid(s);
    const S bound = bricks.at(o + d * tMid) * seg.dt;
    const int k = std::clamp(int(std::ceil(bound / S(layout::kMarchDenseSegmentDepth) - S(1e-3))), 1, layout::kMarchMaxSubsegments);
    if (k == 1) return visit(tMid, seg.dt);
    const S start = tMid - S(0.5) * seg.dt, dt = seg.dt / S(k);
    for (int i = 0; i < k; ++i) visit(start + (S(i) + S(0.5)) * dt, dt);
}

template <typename S>
V3<S> toS(const Vec3d& v) { return V3<S>(S(v.x), S(v.y), S(v.z)); }

template <typename S>
V3<S> applyLinear(const Mat4& m, const V3<S>& v) {
    return {S(m(0, 0)) * v.x + S(m(0, 1)) * v.y + S(m(0, 2)) * v.z,
            S(m(1, 0)) * v.x + S(m(1, 1)) * v.y + S(m(1, 2)) * v.z,
            S(m(2, 0)) * v.x + S(m(2, 1)) * v.y + S(m(2, 2)) * v.z};
}

template <typename S>
S phase(const Phase& ph, S cosTheta) {
    const S inv4pi = S(1) / (S(4) * S(std::numbers::pi));
    if (ph.type == PhaseType::Isotropic) return inv4pi;
    S g = S(ph.g), denom = 1 + g * g + 2 * g * cosTheta;
    return inv4pi * (1 - g * g) / (denom * std::sqrt(denom));
}


}  // namespace volstyle::core::cpu_ref::detail

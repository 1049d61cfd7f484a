#include "core/cpu_ref/reference_renderer.h"

#include "core/cpu_ref/march_ref.h"
#include "core/shaders/layout.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace volstyle::core::cpu_ref {

using namespace detail;

namespace {

/// Bilinear lat-long lookup as GL's linear filter does it (repeat in u, clamp in v).
template <typename S>
V3<S> environment(const Image& env, const V3<S>& dir) {
    S u = S(0.5) + std::atan2(dir.x, -dir.z) / (2 * S(std::numbers::pi));
    S v = std::acos(std::clamp(dir.y, S(-1), S(1))) / S(std::numbers::pi);
    S x = u * env.width - S(0.5), y = v * env.height - S(0.5);
    int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    S fx = x - x0, fy = y - y0;
    auto texel = [&](int xi, int yi) {
        xi = ((xi % env.width) + env.width) % env.width;
        yi = std::clamp(yi, 0, env.height - 1);
        const float* p = env.pixel(xi, yi);
        return V3<S>(S(p[0]), S(p[1]), S(p[2]));
    };
    return (texel(x0, y0) * (1 - fx) + texel(x0 + 1, y0) * fx) * (1 - fy) +
           (texel(x0, y0 + 1) * (1 - fx) + texel(x0 + 1, y0 + 1) * fx) * fy;
}

}  // namespace

template <typename S>
V3<S> opticalDepthToLight(const Volume& volume, const V3<S>& p, const Vec3d& lightDirection, double stepVoxels) {
    const Int3 n = volume.dims();
    const V3<S> d = applyLinear(volume.worldFromIndex().inverseAffine(), toS<S>(normalize(lightDirection)));
    V3<S> tau(S(0));
    auto [tEnter, tExit] = intersectBox(p, d, n);
    tEnter = std::max(tEnter, S(0));
    if (tExit <= tEnter) return tau;
    Segments<S> seg(tEnter, tExit, d, S(stepVoxels));
    for (int s = 0; s < seg.count; ++s) tau += trilinear<S>(volume.extinction(), n, p + d * seg.mid(s)) * seg.dt;
    return tau;
}

template <typename S>
LightDepthGrid<S> lightDepthGrid(const Volume& volume, const Vec3d& lightDirection, double stepVoxels, double across,
                                 double along) {
    const Int3 n = volume.dims();
    if (across <= 0) across = lightGridAcross(maxVoxelDepth(maxComponent(Volume::range(volume.extinction()).second), volume.worldFromIndex()));
    LightDepthGrid<S> g;
    g.volume = &volume;
    g.stepVoxels = stepVoxels;
    g.grid = makeLightGrid(n, volume.worldFromIndex().inverseAffine(), normalize(lightDirection), across, along);
    const Int3 m = g.grid.dims;
    g.depth.assign(size_t(m.volume()) * 3, S(0));
    const V3<S> d = applyLinear(g.grid.indexFromGrid, V3<S>(0, 0, 1));
    const S stepsPerNode = length(d) / S(2 * stepVoxels);  // as light_depth.comp: twice the march step
    const S worldPerNode = length(applyLinear(volume.worldFromIndex(), d));  // σ is per world unit
    // ∫ σ (clamped to the box, as light_depth.comp samples it) over [ta, tb] of o + t d.
    auto integral = [&](const V3<S>& o, S ta, S tb) {
        V3<S> sum(S(0));
        if (!(tb > ta)) return sum;
        const int count = std::max(1, int(std::ceil((tb - ta) * stepsPerNode)));
        const S dt = (tb - ta) / S(count);
        for (int i = 0; i < count; ++i) sum += trilinear<S>(volume.extinction(), n, o + d * (ta + (S(i) + S(0.5)) * dt));
        return sum * (dt * worldPerNode);
    };
    const S reach = S(std::sqrt(2 * across * across + along * along) + 1e-3);  // a cell diagonal
    for (int b = 0; b < m.y; ++b)
        for (int a = 0; a < m.x; ++a) {
            const V3<S> o = toS<S>(g.grid.indexFromGrid.applyPoint({double(a), double(b), 0.0}));
            auto store = [&](int c, const V3<S>& tau) {
                const size_t idx = 3 * ((size_t(c) * m.y + size_t(b)) * m.x + size_t(a));
                g.depth[idx] = tau.x, g.depth[idx + 1] = tau.y, g.depth[idx + 2] = tau.z;
            };
            // As light_depth.comp: the nodes within a cell diagonal of the box, the depth extended
            // past the box from where the row crosses the planes of its light-side faces (t*).
            const auto [tLo, tHi] = intersectBox(o, d, n, reach);
            if (tLo >= tHi) continue;
            const int cFirst = std::max(0, int(std::floor(tLo))), cLast = std::min(m.z - 1, int(std::ceil(tHi)));
            S tStar = S(cFirst - m.z);
            for (int k = 0; k < 3; ++k)
                if (std::abs(d[k]) > S(1e-6) * length(d))
                    tStar = std::max(tStar, ((d[k] > 0 ? S(-0.5) : S(n[k]) - S(0.5)) - o[k]) / d[k]);
            tStar = std::min(tStar, S(cLast + m.z));
            const int c0 = std::max(cFirst, int(std::ceil(tStar)));
            V3<S> tau = c0 <= cLast ? integral(o, tStar, S(c0)) : V3<S>(S(0));
            for (int c = c0; c <= cLast; ++c) {
                if (c > c0 && minComponent(tau) <= S(64)) tau += integral(o, S(c - 1), S(c));
                store(c, tau);
            }
            const int c1 = std::min(cLast, int(std::ceil(tStar)) - 1);
            tau = c1 >= cFirst ? -integral(o, S(c1), tStar) : V3<S>(S(0));
            for (int c = c1; c >= cFirst; --c) {
                if (c < c1) tau = tau - integral(o, S(c), S(c + 1));
                store(c, tau);
            }
        }
    return g;
}

template <typename S>
V3<S> LightDepthGrid<S>::interpolated(const V3<S>& p) const {
    const V3<S> q(S(grid.gridFromIndex(0, 0)) * p.x + S(grid.gridFromIndex(0, 1)) * p.y + S(grid.gridFromIndex(0, 2)) * p.z + S(grid.gridFromIndex(0, 3)),
                  S(grid.gridFromIndex(1, 0)) * p.x + S(grid.gridFromIndex(1, 1)) * p.y + S(grid.gridFromIndex(1, 2)) * p.z + S(grid.gridFromIndex(1, 3)),
                  S(grid.gridFromIndex(2, 0)) * p.x + S(grid.gridFromIndex(2, 1)) * p.y + S(grid.gridFromIndex(2, 2)) * p.z + S(grid.gridFromIndex(2, 3)));
    return trilinear<S>(depth, grid.dims, q);
}

template <typename S>
V3<S> LightDepthGrid<S>::onPlane(const V3<S>& p) const {
    if (grid.alongAxis) return interpolated(p);
    S q[3];
    for (int a = 0; a < 3; ++a)
        q[a] = S(grid.gridFromIndex(a, 0)) * p.x + S(grid.gridFromIndex(a, 1)) * p.y + S(grid.gridFromIndex(a, 2)) * p.z + S(grid.gridFromIndex(a, 3));
    const Int3 n = grid.dims;
    const int plane = std::clamp(int(std::lround(q[2])), 0, n.z - 1);
    int i0[2];
    S w[2][4];
    for (int a = 0; a < 2; ++a) {
        const S qa = std::clamp(q[a], S(0), S(n[a] - 1));
        i0[a] = std::min(int(std::floor(qa)), n[a] - 1);
        const S t = qa - S(i0[a]), t2 = t * t, t3 = t2 * t;
        w[a][0] = S(-0.5) * t3 + t2 - S(0.5) * t, w[a][1] = S(1.5) * t3 - S(2.5) * t2 + 1;
        w[a][2] = S(-1.5) * t3 + 2 * t2 + S(0.5) * t, w[a][3] = S(0.5) * t3 - S(0.5) * t2;
    }
    V3<S> sum(S(0)), lo(std::numeric_limits<S>::max()), hi(-std::numeric_limits<S>::max());
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
            const int x = std::clamp(i0[0] + a - 1, 0, n.x - 1), y = std::clamp(i0[1] + b - 1, 0, n.y - 1);
            const size_t idx = 3 * ((size_t(plane) * n.y + size_t(y)) * n.x + size_t(x));
            const V3<S> v(depth[idx], depth[idx + 1], depth[idx + 2]);
            sum += v * (w[0][a] * w[1][b]);
            if ((a == 1 || a == 2) && (b == 1 || b == 2))
                for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v[c]), hi[c] = std::max(hi[c], v[c]);
        }
    for (int c = 0; c < 3; ++c) sum[c] = std::clamp(sum[c], lo[c], hi[c]);
    return sum;
}

template <typename S>
V3<S> LightDepthGrid<S>::at(const V3<S>& p) const {
    // lighting.glsl's lightDepthAt, step for step (its comment says why).
    const Int3 n = volume->dims();
    const V3<S> toLight = -applyLinear(grid.indexFromGrid, V3<S>(0, 0, 1));  // one node toward the light
    const S nodeVoxels = length(toLight);
    const S worldPerNode = length(applyLinear(volume->worldFromIndex(), toLight));
    const S stepsPerNode = nodeVoxels / S(stepVoxels);
    const S exitNodes = std::max(intersectBox(p, toLight, n).second, S(0));
    const S gz = S(grid.gridFromIndex(2, 0)) * p.x + S(grid.gridFromIndex(2, 1)) * p.y + S(grid.gridFromIndex(2, 2)) * p.z +
                 S(grid.gridFromIndex(2, 3));
    V3<S> tau(S(0));
    S s0 = 0, s1 = gz - std::floor(gz);
    for (int k = 0;; ++k) {
        const S s1Box = std::min(s1, exitNodes);
        V3<S> span(S(0));
        if (s1Box > s0) {
            const int count = std::max(1, int(std::ceil((s1Box - s0) * stepsPerNode - S(1e-3))));  // as the GLSL
            const S ds = (s1Box - s0) / S(count);
            for (int i = 0; i < count; ++i) span += trilinear<S>(volume->extinction(), n, p + toLight * (s0 + (S(i) + S(0.5)) * ds));
            span = span * (ds * worldPerNode);
        }
        tau += span;
        if (exitNodes <= s1 || minComponent(tau) >= S(layout::kLightMarchOpaque)) return tau;
        if (k >= layout::kLightMarchMaxSpans || (s1 >= S(layout::kLightMarchMinNodes) && maxComponent(span) < S(layout::kLightMarchDenseSpan))) {
            const V3<S> g = onPlane(p + toLight * s1);
            return tau + V3<S>(std::max(g.x, S(0)), std::max(g.y, S(0)), std::max(g.z, S(0)));
        }
        s0 = s1;
        s1 += 1;
    }
}

template <typename S>
LightDepthLookup<S>::LightDepthLookup(const Volume& volume, const Vec3d& lightDirection, double stepVoxels,
                                      LightDepthMethod method)
    : m_volume(volume), m_direction(lightDirection), m_step(stepVoxels), m_method(method) {
    if (method == LightDepthMethod::Grid) m_grid = lightDepthGrid<S>(volume, lightDirection, stepVoxels);
    if (method == LightDepthMethod::GridAlone) m_grid = lightDepthGrid<S>(volume, lightDirection, stepVoxels, kLightGridSpacing);
    if (method == LightDepthMethod::VoxelCentres) {
        const Int3 n = volume.dims();
        m_voxelCentres.assign(volume.voxelCount() * 3, S(0));
        for (int k = 0; k < n.z; ++k)
            for (int j = 0; j < n.y; ++j)
                for (int i = 0; i < n.x; ++i) {
                    const V3<S> tau = opticalDepthToLight<S>(volume, V3<S>(S(i), S(j), S(k)), lightDirection, stepVoxels);
                    const size_t idx = 3 * volume.index(i, j, k);
                    m_voxelCentres[idx] = tau.x, m_voxelCentres[idx + 1] = tau.y, m_voxelCentres[idx + 2] = tau.z;
                }
    }
}

template <typename S>
V3<S> LightDepthLookup<S>::at(const V3<S>& p) const {
    switch (m_method) {
        case LightDepthMethod::Grid: return m_grid.at(p);
        case LightDepthMethod::GridAlone: return m_grid.interpolated(p);
        case LightDepthMethod::Exact: return opticalDepthToLight<S>(m_volume, p, m_direction, m_step);
        case LightDepthMethod::VoxelCentres: return trilinear<S>(m_voxelCentres, m_volume.dims(), p);
    }
    return V3<S>(S(0));
}

/// The environment's lobes as the GL path holds them (core/render/lobe_volumes.h): per lobe the
/// transmittance e^{−τ} at the nodes of the light volumes' grid, τ by `method`, trilinear between.
template <typename S>
struct LobesRef {
    std::vector<Vec3d> direction, irradiance;  // toward the lobe; its radiance × solid angle
    std::vector<std::vector<S>> transmittance;  // per lobe, 3 per node
    Int3 dims;
    V3<S> scale;

    LobesRef(const Volume& volume, const EnvironmentLight& env, double stepVoxels, LightDepthMethod method) {
        if (!env.active()) return;
        const std::vector<Vec3d> radiance = lobeRadiance(env);
        const LobeBasis basis = env.basis();
        const std::vector<double> omega = basis.solidAngles();
        const Int3 n = volume.dims();
        dims = lobeGridDims(n, env.lightVolumeResolution);
        scale = V3<S>(S(dims.x) / S(n.x), S(dims.y) / S(n.y), S(dims.z) / S(n.z));
        for (int i = 0; i < basis.size(); ++i) {
            if (maxComponent(radiance[size_t(i)]) <= 0) continue;
            direction.push_back(basis.directions[size_t(i)]);
            irradiance.push_back(radiance[size_t(i)] * omega[size_t(i)]);
            // As lobe_volumes.cpp: the grid alone, rows a voxel apart (no march from each node).
            const LightDepthLookup<S> depth(volume, basis.directions[size_t(i)], stepVoxels,
                                            method == LightDepthMethod::Grid ? LightDepthMethod::GridAlone : method);
            std::vector<S> t(size_t(dims.volume()) * 3);
            for (int k = 0; k < dims.z; ++k)
                for (int j = 0; j < dims.y; ++j)
                    for (int a = 0; a < dims.x; ++a) {
                        const V3<S> node{S(a), S(j), S(k)};
                        const V3<S> tau = depth.at((node + V3<S>(S(0.5))) / scale - V3<S>(S(0.5)));
                        const size_t idx = 3 * ((size_t(k) * dims.y + size_t(j)) * dims.x + size_t(a));
                        t[idx] = std::exp(-tau.x), t[idx + 1] = std::exp(-tau.y), t[idx + 2] = std::exp(-tau.z);
                    }
            transmittance.push_back(std::move(t));
        }
    }

    /// Σ_i p(ω_i·(−ω)) E_i T_i(p) at index-space point p.
    V3<S> inScattering(const V3<S>& p, const V3<S>& dir, const Phase& ph) const {
        V3<S> sum(S(0));
        const V3<S> q = (p + V3<S>(S(0.5))) * scale - V3<S>(S(0.5));
        for (size_t i = 0; i < direction.size(); ++i)
            sum += toS<S>(irradiance[i]) * trilinear<S>(transmittance[i], dims, q) * phase<S>(ph, dot(toS<S>(direction[i]), -dir));
        return sum;
    }
};

template <typename S>
Image renderReference(const Volume& volume, const Camera& camera, const Lighting& lighting, double stepVoxels,
                      LightDepthMethod method, double lightStepVoxels) {
    const double lightStep = method == LightDepthMethod::Exact && lightStepVoxels > 0 ? lightStepVoxels : stepVoxels;
    camera.validate();
    lighting.validate();
    requireDense(volume, "the reference renderer");
    const Int3 n = volume.dims();
    const Mat4 indexFromWorld = volume.worldFromIndex().inverseAffine();

    std::vector<const DirectionalLight*> lights;
    std::vector<LightDepthLookup<S>> depths;
    for (const auto& l : lighting.lights) {
        if (maxComponent(l.irradiance) <= 0) continue;
        lights.push_back(&l);
        depths.emplace_back(volume, l.direction, lightStep, method);
    }
    const LobesRef<S> lobes(volume, lighting.environment, stepVoxels, method);
    // The lobes seen directly as the background: each direction its cell's radiance.
    const bool lobeBackground = lighting.background.fromLobes && lighting.environment.active() && !lighting.background.plate;
    const LobeBasis backgroundBasis = lobeBackground ? lighting.environment.basis() : LobeBasis{};
    const std::vector<Vec3d> backgroundRadiance = lobeBackground ? lobeRadiance(lighting.environment) : std::vector<Vec3d>{};

    const BrickBound bricks(volume.extinction(), n);
    Image image(camera.width, camera.height);
    const V3<S> eyeIndex = toS<S>(indexFromWorld.applyPoint(camera.eye));
    for (int py = 0; py < camera.height; ++py)
        for (int px = 0; px < camera.width; ++px) {
            const V3<S> dir = toS<S>(camera.rayDirection(px, py));
            const V3<S> d = applyLinear(indexFromWorld, dir);
            auto [t0, t1] = intersectBox(eyeIndex, d, n);
            t0 = std::max(t0, S(camera.nearDist));
            t1 = std::min(t1, S(camera.farDist));
            V3<S> L(S(0)), T(S(1));
            if (t0 < t1) {
                Segments<S> seg(t0, t1, d, S(stepVoxels));
                for (int s = 0; s < seg.count; ++s) forEachSubsegment(seg, s, eyeIndex, d, bricks, [&](S tMid, S dt) {
                    const V3<S> p = eyeIndex + d * tMid;
                    const V3<S> sigma = trilinear<S>(volume.extinction(), n, p);
                    if (maxComponent(sigma) <= 0) return;
                    V3<S> Lm = volume.hasEmission() ? trilinear<S>(volume.emission(), n, p) : V3<S>(S(0));
                    if (!lights.empty() || !lobes.direction.empty()) {
                        V3<S> albedo = volume.hasAlbedo() ? trilinear<S>(volume.albedo(), n, p) : V3<S>(S(1));
                        V3<S> scat(S(0));
                        for (size_t l = 0; l < lights.size(); ++l) {
                            V3<S> tau = depths[l].at(p);
                            S cosTheta = dot(toS<S>(normalize(lights[l]->direction)), -dir);
                            V3<S> Tl(std::exp(-tau.x), std::exp(-tau.y), std::exp(-tau.z));
                            scat += toS<S>(lights[l]->irradiance) * Tl * phase<S>(lighting.phase, cosTheta);
                        }
                        if (!lobes.direction.empty()) scat += lobes.inScattering(p, dir, lighting.phase);
                        Lm += albedo * scat;
                    }
                    const V3<S> tau = sigma * dt;
                    const V3<S> segT(std::exp(-tau.x), std::exp(-tau.y), std::exp(-tau.z));
                    const V3<S> alpha(-std::expm1(-tau.x), -std::expm1(-tau.y), -std::expm1(-tau.z));
                    L += T * alpha * Lm;
                    T = T * segT;
                });
            }
            const Background& bg = lighting.background;
            const float* plate = bg.plate ? bg.plate->pixel(px, py) : nullptr;
            const int cell = lobeBackground ? backgroundBasis.cellOf(camera.rayDirection(px, py)) : -1;
            L += T * (plate              ? V3<S>(S(plate[0]), S(plate[1]), S(plate[2]))
                      : cell >= 0      ? toS<S>(backgroundRadiance[size_t(cell)])
                      : bg.environment ? environment<S>(*bg.environment, dir)
                                       : toS<S>(bg.color));
            float* out = image.pixel(px, py);
            out[0] = float(L.x), out[1] = float(L.y), out[2] = float(L.z);
            out[3] = float(1 - (T.x + T.y + T.z) / 3);
        }
    return image;
}

template Image renderReference<double>(const Volume&, const Camera&, const Lighting&, double, LightDepthMethod, double);
template Image renderReference<float>(const Volume&, const Camera&, const Lighting&, double, LightDepthMethod, double);
template Vec3T<double> opticalDepthToLight<double>(const Volume&, const Vec3T<double>&, const Vec3d&, double);
template struct LightDepthGrid<double>;
template LightDepthGrid<double> lightDepthGrid<double>(const Volume&, const Vec3d&, double, double, double);
template class LightDepthLookup<double>;
template class LightDepthLookup<float>;

}  // namespace volstyle::core::cpu_ref

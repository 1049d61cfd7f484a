#include "core/cpu_ref/reference_renderer.h"

#include "core/cpu_ref/march_ref.h"

#include <algorithm>
#include <cmath>
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
std::vector<S> lightDepthVolume(const Volume& volume, const Vec3d& lightDirection, double stepVoxels) {
    const Int3 n = volume.dims();
    const Mat4 indexFromWorld = volume.worldFromIndex().inverseAffine();
    const V3<S> d = applyLinear(indexFromWorld, toS<S>(normalize(lightDirection)));
    std::vector<S> depth(volume.voxelCount() * 3, S(0));
    for (int k = 0; k < n.z; ++k)
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
                V3<S> o{S(i), S(j), S(k)};
                S tExit = intersectBox(o, d, n).second;
                if (tExit <= 0) continue;
                Segments<S> seg(S(0), tExit, d, S(stepVoxels));
                V3<S> tau(S(0));
                for (int s = 0; s < seg.count; ++s) {
                    tau += trilinear<S>(volume.extinction(), n, o + d * seg.mid(s)) * seg.dt;
                    if (minComponent(tau) > S(64)) break;  // as light_depth.comp
                }
                size_t idx = 3 * volume.index(i, j, k);
                depth[idx] = tau.x, depth[idx + 1] = tau.y, depth[idx + 2] = tau.z;
            }
    return depth;
}

template <typename S>
Image renderReference(const Volume& volume, const Camera& camera, const Lighting& lighting, double stepVoxels) {
    camera.validate();
    lighting.validate();
    const Int3 n = volume.dims();
    const Mat4 indexFromWorld = volume.worldFromIndex().inverseAffine();

    std::vector<const DirectionalLight*> lights;
    std::vector<std::vector<S>> depths;
    for (const auto& l : lighting.lights) {
        if (maxComponent(l.irradiance) <= 0) continue;
        lights.push_back(&l);
        depths.push_back(lightDepthVolume<S>(volume, l.direction, stepVoxels));
    }

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
                for (int s = 0; s < seg.count; ++s) {
                    const V3<S> p = eyeIndex + d * seg.mid(s);
                    const V3<S> sigma = trilinear<S>(volume.extinction(), n, p);
                    V3<S> Lm = volume.hasEmission() ? trilinear<S>(volume.emission(), n, p) : V3<S>(S(0));
                    if (!lights.empty()) {
                        V3<S> albedo = volume.hasAlbedo() ? trilinear<S>(volume.albedo(), n, p) : V3<S>(S(1));
                        V3<S> scat(S(0));
                        for (size_t l = 0; l < lights.size(); ++l) {
                            V3<S> tau = trilinear<S>(depths[l], n, p);
                            S cosTheta = dot(toS<S>(normalize(lights[l]->direction)), -dir);
                            V3<S> Tl(std::exp(-tau.x), std::exp(-tau.y), std::exp(-tau.z));
                            scat += toS<S>(lights[l]->irradiance) * Tl * phase<S>(lighting.phase, cosTheta);
                        }
                        Lm += albedo * scat;
                    }
                    const V3<S> tau = sigma * seg.dt;
                    const V3<S> segT(std::exp(-tau.x), std::exp(-tau.y), std::exp(-tau.z));
                    const V3<S> alpha(-std::expm1(-tau.x), -std::expm1(-tau.y), -std::expm1(-tau.z));
                    L += T * alpha * Lm;
                    T = T * segT;
                }
            }
            L += T * (lighting.background.environment ? environment<S>(*lighting.background.environment, dir)
                                                      : toS<S>(lighting.background.color));
            float* out = image.pixel(px, py);
            out[0] = float(L.x), out[1] = float(L.y), out[2] = float(L.z);
            out[3] = float(1 - (T.x + T.y + T.z) / 3);
        }
    return image;
}

template Image renderReference<double>(const Volume&, const Camera&, const Lighting&, double);
template Image renderReference<float>(const Volume&, const Camera&, const Lighting&, double);
template std::vector<double> lightDepthVolume<double>(const Volume&, const Vec3d&, double);

}  // namespace volstyle::core::cpu_ref

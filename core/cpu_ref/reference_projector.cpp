#include "core/cpu_ref/reference_projector.h"

#include "core/cpu_ref/march_ref.h"
#include "core/cpu_ref/reference_renderer.h"

namespace volstyle::core::cpu_ref {

using namespace detail;
using V = Vec3T<double>;

ReferenceProjector::ReferenceProjector(const Volume& volume, const Lighting& lighting,
                                       const std::vector<Camera>& cameras, const ProjectionSpec& spec)
    : m_volume(volume), m_lighting(lighting), m_cameras(cameras), m_spec(spec) {
    m_lighting.lights.erase(std::remove_if(m_lighting.lights.begin(), m_lighting.lights.end(),
                                           [](const DirectionalLight& l) { return maxComponent(l.irradiance) <= 0; }),
                            m_lighting.lights.end());
    for (const auto& l : m_lighting.lights) m_lightDepth.push_back(lightDepthGrid<double>(volume, l.direction, spec.stepVoxels));
    for (const auto& c : cameras) m_pixelCount += size_t(c.width) * c.height;
    m_bricks = std::make_shared<const detail::BrickBound>(volume.extinction(), volume.dims());
}

size_t ReferenceProjector::elementCount() const {
    return size_t(m_spec.unknownDims.volume()) * (m_spec.unknown == Unknown::EmissionAlbedo ? 2 : 1);
}

template <typename Visit>
void ReferenceProjector::march(size_t view, int px, int py, Visit&& visit) const {
    const Camera& cam = m_cameras[view];
    const Int3 n = m_volume.dims(), nu = m_spec.unknownDims;
    const Mat4 indexFromWorld = m_volume.worldFromIndex().inverseAffine();
    const V dir = toS<double>(cam.rayDirection(px, py));
    const V o = toS<double>(indexFromWorld.applyPoint(cam.eye));
    const V d = applyLinear(indexFromWorld, dir);
    auto [t0, t1] = intersectBox(o, d, n);
    t0 = std::max(t0, cam.nearDist);
    t1 = std::min(t1, cam.farDist);
    if (!(t0 < t1)) return;
    Segments<double> seg(t0, t1, d, m_spec.stepVoxels);
    const V scale(double(nu.x) / n.x, double(nu.y) / n.y, double(nu.z) / n.z);

    // The basis functions at p (extinction index space), over the unknown grid.
    auto basis = [&](const V& p, size_t block, const V& weight) {
        V q = (p + V(0.5)) * scale - V(0.5);
        if (m_spec.basis == BasisType::Box) {
            int c[3];
            for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor(q[a] + 0.5)), 0, nu[a] - 1);
            visit(block + (size_t(c[2]) * nu.y + size_t(c[1])) * nu.x + size_t(c[0]), weight);
            return;
        }
        int i0[3], i1[3];
        double f[3];
        for (int a = 0; a < 3; ++a) {
            double qa = std::clamp(q[a], 0.0, double(nu[a] - 1));
            i0[a] = std::min(int(std::floor(qa)), nu[a] - 1);
            i1[a] = std::min(i0[a] + 1, nu[a] - 1);
            f[a] = qa - i0[a];
        }
        for (int c = 0; c < 8; ++c) {
            int x = (c & 1) ? i1[0] : i0[0], y = (c & 2) ? i1[1] : i0[1], z = (c & 4) ? i1[2] : i0[2];
            double w = ((c & 1) ? f[0] : 1 - f[0]) * ((c & 2) ? f[1] : 1 - f[1]) * ((c & 4) ? f[2] : 1 - f[2]);
            visit(block + (size_t(z) * nu.y + size_t(y)) * nu.x + size_t(x), weight * w);
        }
    };

    if (m_spec.unknown == Unknown::Extinction) {
        for (int s = 0; s < seg.count; ++s) basis(o + d * seg.mid(s), 0, V(seg.dt));
        return;
    }
    const size_t albedoBlock = m_spec.unknown == Unknown::EmissionAlbedo ? size_t(nu.volume()) : 0;
    const BrickBound& bricks = *m_bricks;
    V T(1.0);
    bool done = false;
    for (int s = 0; s < seg.count && !done; ++s) forEachSubsegment(seg, s, o, d, bricks, [&](double tMid, double dt) {
        if (done) return;
        const V p = o + d * tMid;
        const V sigma = trilinear<double>(m_volume.extinction(), n, p);
        if (maxComponent(sigma) <= 0) return;
        const V tau = sigma * dt;
        const V opacity = T * V(-std::expm1(-tau.x), -std::expm1(-tau.y), -std::expm1(-tau.z));
        if (m_spec.unknown != Unknown::Albedo) basis(p, 0, opacity);
        if (m_spec.unknown != Unknown::Emission) {
            V scat(0.0);
            for (size_t l = 0; l < m_lighting.lights.size(); ++l) {
                V depth = m_lightDepth[l].at(p);
                double cosTheta = dot(toS<double>(normalize(m_lighting.lights[l].direction)), -dir);
                scat += toS<double>(m_lighting.lights[l].irradiance) * V(std::exp(-depth.x), std::exp(-depth.y), std::exp(-depth.z)) *
                        phase<double>(m_lighting.phase, cosTheta);
            }
            basis(p, albedoBlock, opacity * scat);
        }
        T = T * V(std::exp(-tau.x), std::exp(-tau.y), std::exp(-tau.z));
        done = maxComponent(T) < 1e-8;  // as project.comp
    });
}

std::vector<double> ReferenceProjector::forward(const std::vector<double>& a) const {
    std::vector<double> out(m_pixelCount * 4, 0.0);
    size_t pixel = 0;
    for (size_t v = 0; v < m_cameras.size(); ++v)
        for (int py = 0; py < m_cameras[v].height; ++py)
            for (int px = 0; px < m_cameras[v].width; ++px, ++pixel)
                march(v, px, py, [&](size_t e, const V& w) {
                    for (int c = 0; c < 3; ++c) out[4 * pixel + size_t(c)] += w[c] * a[4 * e + size_t(c)];
                });
    return out;
}

std::vector<double> ReferenceProjector::adjoint(const std::vector<double>& r) const {
    std::vector<double> out(elementCount() * 4, 0.0);
    size_t pixel = 0;
    for (size_t v = 0; v < m_cameras.size(); ++v)
        for (int py = 0; py < m_cameras[v].height; ++py)
            for (int px = 0; px < m_cameras[v].width; ++px, ++pixel)
                march(v, px, py, [&](size_t e, const V& w) {
                    for (int c = 0; c < 3; ++c) out[4 * e + size_t(c)] += w[c] * r[4 * pixel + size_t(c)];
                });
    return out;
}

}  // namespace volstyle::core::cpu_ref

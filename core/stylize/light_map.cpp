#include "core/stylize/light_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>

namespace volstyle::core {
namespace {

/// An orthonormal frame with w along `axis`.
void frameAround(const Vec3d& axis, Vec3d& u, Vec3d& v, Vec3d& w) {
    w = normalize(axis);
    const Vec3d helper = std::abs(w.y) < 0.9 ? Vec3d(0, 1, 0) : Vec3d(1, 0, 0);
    u = normalize(cross(helper, w));
    v = cross(w, u);
}

}  // namespace

/// World-space bounds of an occluder after its transform.
std::pair<Vec3d, Vec3d> occluderBounds(const Occluder& o) {
    Vec3d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    auto [a, b] = o.mesh->bounds();
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3d p = o.worldFromObject.applyPoint({(corner & 1) ? b.x : a.x, (corner & 2) ? b.y : a.y, (corner & 4) ? b.z : a.z});
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    return {lo, hi};
}

/// The camera in the map's texel coordinates and depth (Eq. 3's epipole l, z_l).
Epipole epipoleOf(const Mat4& lightClip, const Vec3d& eye, int n) {
    double h[4];
    for (int r = 0; r < 4; ++r) h[r] = lightClip(r, 0) * eye.x + lightClip(r, 1) * eye.y + lightClip(r, 2) * eye.z + lightClip(r, 3);
    Epipole e;
    const double w = std::abs(h[3]) < 1e-12 ? 1e-12 : h[3];  // a camera in the spot's plane: the epipole at infinity
    e.x = (h[0] / w * 0.5 + 0.5) * n;
    e.y = (h[1] / w * 0.5 + 0.5) * n;
    e.depth = h[2] / w * 0.5 + 0.5;
    e.sense = w > 0 ? 1 : -1;
    return e;
}

/// Where the map's texels sit in noise coordinates: `frequency` times world units across the
/// beams (directional: the light-plane position; spot: the cone's tangent plane scaled to the
/// object's distance `spotScale` = tan(cone/2)·distance).
HoleMap holeMapOf(const Mat4& lightClip, bool spot, double spotScale, int n, double frequency) {
    HoleMap h;
    if (spot) {
        h.originX = h.originY = -frequency * spotScale;
        h.stepX = h.stepY = frequency * spotScale * 2 / n;
        return h;
    }
    // Orthographic: ndc_x = |r0| (p·u − a_x)·… so p·u at texel 0's corner is a_x = −(m03 + 1)/|r0|.
    const double r0 = length(Vec3d(lightClip(0, 0), lightClip(0, 1), lightClip(0, 2)));
    const double r1 = length(Vec3d(lightClip(1, 0), lightClip(1, 1), lightClip(1, 2)));
    h.originX = -frequency * (lightClip(0, 3) + 1) / r0;
    h.originY = -frequency * (lightClip(1, 3) + 1) / r1;
    h.stepX = frequency * 2 / (r0 * n);
    h.stepY = frequency * 2 / (r1 * n);
    return h;
}

/// OpenGL's perspective projection: tan of half the vertical field, width / height, clip planes.
Mat4 perspective(double tanHalfY, double aspect, double nearDist, double farDist) {
    Mat4 proj;
    proj(0, 0) = 1 / (tanHalfY * aspect);
    proj(1, 1) = 1 / tanHalfY;
    proj(2, 2) = -(farDist + nearDist) / (farDist - nearDist);
    proj(2, 3) = -2 * farDist * nearDist / (farDist - nearDist);
    proj(3, 2) = -1;
    proj(3, 3) = 0;
    return proj;
}

/// OpenGL's perspective projection of the pinhole camera (pixel centres as camera.glsl's rays).
Mat4 cameraClipFromWorld(const Camera& cam, double nearDist, double farDist) {
    const Camera::Frame f = cam.frame();
    Mat4 view;
    for (int c = 0; c < 3; ++c) view(0, c) = f.right[c], view(1, c) = f.up[c], view(2, c) = -f.forward[c];
    view(0, 3) = -dot(f.right, cam.eye), view(1, 3) = -dot(f.up, cam.eye), view(2, 3) = dot(f.forward, cam.eye);
    return perspective(cam.tanHalfFov(), double(cam.width) / cam.height, nearDist, farDist) * view;
}

Mat4 lightClipFromWorld(const Vec3d& towardLight, const Vec3d& lo, const Vec3d& hi, int n, int marginTexels) {
    Vec3d u, v, w;
    frameAround(towardLight, u, v, w);
    Vec3d a(std::numeric_limits<double>::max()), b(-std::numeric_limits<double>::max());
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3d p((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y, (corner & 4) ? hi.z : lo.z);
        const Vec3d q(dot(p, u), dot(p, v), dot(p, w));
        for (int k = 0; k < 3; ++k) a[k] = std::min(a[k], q[k]), b[k] = std::max(b[k], q[k]);
    }
    // A margin so geometry on the bounds is not clipped; depth grows away from the light.
    for (int k = 0; k < 3; ++k) {
        double pad = 1e-3 * std::max(b[k] - a[k], 1e-6) + 1e-6;
        if (k < 2 && marginTexels > 0)  // the extent grows to n texels of which 2·margin are empty
            pad += std::max(b[k] - a[k], 1e-6) * marginTexels / std::max(n - 2 * marginTexels, 1);
        a[k] -= pad, b[k] += pad;
    }
    Mat4 m;
    for (int c = 0; c < 3; ++c) {
        m(0, c) = 2 * u[c] / (b.x - a.x);
        m(1, c) = 2 * v[c] / (b.y - a.y);
        m(2, c) = -2 * w[c] / (b.z - a.z);
    }
    m(0, 3) = -2 * a.x / (b.x - a.x) - 1;
    m(1, 3) = -2 * a.y / (b.y - a.y) - 1;
    m(2, 3) = 2 * b.z / (b.z - a.z) - 1;
    return m;
}

Mat4 spotClipFromWorld(const Vec3d& position, const Vec3d& towardLight, double coneDeg, const Vec3d& lo, const Vec3d& hi) {
    Vec3d u, v, w;
    frameAround(towardLight, u, v, w);  // the spot looks along −w
    double farthest = 0, nearest = std::numeric_limits<double>::max();
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3d p = Vec3d((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y, (corner & 4) ? hi.z : lo.z) - position;
        farthest = std::max(farthest, length(p));
        nearest = std::min(nearest, -dot(p, w));
    }
    const double farPlane = std::max(farthest * 1.01, 1e-3);
    const double nearPlane = std::clamp(nearest * 0.99, farPlane * 1e-4, farPlane * 0.5);
    Mat4 view;
    for (int c = 0; c < 3; ++c) view(0, c) = u[c], view(1, c) = v[c], view(2, c) = w[c];
    view(0, 3) = -dot(u, position), view(1, 3) = -dot(v, position), view(2, 3) = -dot(w, position);
    return perspective(std::tan(coneDeg * 0.5 * std::numbers::pi / 180), 1, nearPlane, farPlane) * view;
}

LightMap lightMapOf(const StylizerScene& scene) {
    LightMap m;
    for (const Occluder& o : scene.occluders) m.objectBounds.push_back(occluderBounds(o));
    if (m.objectBounds.empty()) {
        m.lo = Vec3d(-1.0), m.hi = Vec3d(1.0);  // nothing to cover: a unit box
    } else {
        std::tie(m.lo, m.hi) = m.objectBounds[0];
        for (const auto& [a, b] : m.objectBounds)
            for (int k = 0; k < 3; ++k) m.lo[k] = std::min(m.lo[k], a[k]), m.hi[k] = std::max(m.hi[k], b[k]);
    }
    const StylizerLight& light = scene.light;
    const int n = light.shadowMapSize;
    m.spot = light.type == StylizerLightType::Spot;
    const Vec3d toLight = normalize(light.direction);
    int margin = 0;  // texels kept empty around the occluders: the largest closing radius
    for (const Occluder& o : scene.occluders) margin = std::max(margin, o.manipulation.closingRadius + o.manipulation.erosionPx);
    m.clip = m.spot ? spotClipFromWorld(light.position, toLight, light.coneDeg, m.lo, m.hi) : lightClipFromWorld(toLight, m.lo, m.hi, n, margin);
    m.spotTan = std::tan(light.coneDeg * 0.5 * std::numbers::pi / 180);
    m.texel = m.spot ? 2 * m.spotTan / n
                     : std::max(2 / length(Vec3d(m.clip(0, 0), m.clip(0, 1), m.clip(0, 2))),
                                2 / length(Vec3d(m.clip(1, 0), m.clip(1, 1), m.clip(1, 2)))) / n;
    return m;
}

/// Eq. 3's kernel for occluder `i`, in texels where the object is (a spot's grow with distance).
int dilationTexels(const LightMap& map, const StylizerScene& scene, size_t i) {
    const auto& [lo, hi] = map.objectBounds[i];
    const double objectTexel = map.spot ? map.texel * length((lo + hi) * 0.5 - scene.light.position) : map.texel;
    const int n = scene.light.shadowMapSize;
    return int(std::min(double(n), std::round(scene.occluders[i].manipulation.dilationLength / objectTexel)));
}

}  // namespace volstyle::core

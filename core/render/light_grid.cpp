#include "core/render/light_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace volstyle::core {

double maxVoxelDepth(double maxExtinction, const Mat4& worldFromIndex) {
    double edge = 0;
    for (int a = 0; a < 3; ++a) edge = std::max(edge, length(worldFromIndex.applyVector(Vec3d(a == 0, a == 1, a == 2))));
    return maxExtinction * edge;
}

double lightGridAcross(double voxelDepth) { return voxelDepth >= kDenseVoxelDepth ? 0.5 * kLightGridSpacing : kLightGridSpacing; }

LightGrid makeLightGrid(Int3 volumeDims, const Mat4& indexFromWorld, const Vec3d& towardLight, double across, double along) {
    return makeLightGrid(Vec3d(-0.5), Vec3d(volumeDims.x - 0.5, volumeDims.y - 0.5, volumeDims.z - 0.5), indexFromWorld, towardLight,
                         across, along);
}

LightGrid makeLightGrid(const Vec3d& boxLo, const Vec3d& boxHi, const Mat4& indexFromWorld, const Vec3d& towardLight, double across,
                        double along) {
    // An orthonormal frame in index space: w toward the light, u and v across the beam.
    const Vec3d w = normalize(indexFromWorld.applyVector(towardLight));
    const int minor = std::abs(w.x) <= std::abs(w.y) && std::abs(w.x) <= std::abs(w.z) ? 0 : (std::abs(w.y) <= std::abs(w.z) ? 1 : 2);
    Vec3d axis(0.0);
    axis[minor] = 1;
    const Vec3d uAxis = normalize(cross(axis, w));
    const Vec3d vAxis = cross(w, uAxis);

    // The box's extent in that frame.
    Vec3d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3d p((corner & 1) ? boxHi.x : boxLo.x, (corner & 2) ? boxHi.y : boxLo.y, (corner & 4) ? boxHi.z : boxLo.z);
        const Vec3d q(dot(p, uAxis), dot(p, vAxis), dot(p, w));
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], q[a]), hi[a] = std::max(hi[a], q[a]);
    }
    // Anchor nodes at multiples of the spacing from index 0: across the beam from below, along it
    // from the light side (the first node of a row lies on or beyond the box, where the depth is 0).
    const double h = across, hz = along;
    const double u0 = std::floor(lo.x / h) * h, v0 = std::floor(lo.y / h) * h, wTop = std::ceil(hi.z / hz) * hz;
    LightGrid g;
    // (A rotated grid can leave ~1e-17 in the other components of an axis-aligned light.)
    g.alongAxis = int(std::abs(w.x) < 1e-9) + int(std::abs(w.y) < 1e-9) + int(std::abs(w.z) < 1e-9) == 2;
    g.dims = {int(std::ceil((hi.x - u0) / h)) + 1, int(std::ceil((hi.y - v0) / h)) + 1,
              int(std::ceil((wTop - lo.z) / hz)) + 1};

    // grid = ((p·u − u0)/h, (p·v − v0)/h, (wTop − p·w)/h); its inverse from the orthonormal frame.
    Mat4& f = g.gridFromIndex;
    for (int c = 0; c < 3; ++c) {
        f(0, c) = uAxis[c] / h;
        f(1, c) = vAxis[c] / h;
        f(2, c) = -w[c] / hz;
    }
    f(0, 3) = -u0 / h, f(1, 3) = -v0 / h, f(2, 3) = wTop / hz;
    Mat4& b = g.indexFromGrid;
    for (int r = 0; r < 3; ++r) {
        b(r, 0) = uAxis[r] * h;
        b(r, 1) = vAxis[r] * h;
        b(r, 2) = -w[r] * hz;
        b(r, 3) = u0 * uAxis[r] + v0 * vAxis[r] + wTop * w[r];
    }
    return g;
}

}  // namespace volstyle::core

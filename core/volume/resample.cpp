#include "core/volume/resample.h"

#include <algorithm>
#include <cmath>

namespace volstyle::core {

Vec3d sampleGrid(const GridView& g, const Vec3d& q, BasisType basis) {
    const Int3 n = g.dims;
    auto at = [&](int x, int y, int z) {
        const size_t voxel = g.bricks ? g.bricks->storageIndex({x, y, z}) : (size_t(z) * n.y + size_t(y)) * n.x + size_t(x);
        const size_t i = g.offset + size_t(g.stride) * voxel;
        return Vec3d(g.data[i], g.data[i + 1], g.data[i + 2]);
    };
    if (basis == BasisType::Box) {
        int c[3];
        for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor(q[a] + 0.5)), 0, n[a] - 1);
        return at(c[0], c[1], c[2]);
    }
    int i0[3], i1[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
        double qa = std::clamp(q[a], 0.0, double(n[a] - 1));
        i0[a] = std::min(int(std::floor(qa)), n[a] - 1);
        i1[a] = std::min(i0[a] + 1, n[a] - 1);
        f[a] = qa - i0[a];
    }
    Vec3d r(0.0);
    for (int c = 0; c < 8; ++c) {
        double w = ((c & 1) ? f[0] : 1 - f[0]) * ((c & 2) ? f[1] : 1 - f[1]) * ((c & 4) ? f[2] : 1 - f[2]);
        if (w != 0) r += at((c & 1) ? i1[0] : i0[0], (c & 2) ? i1[1] : i0[1], (c & 4) ? i1[2] : i0[2]) * w;
    }
    return r;
}

std::vector<float> resample(const GridView& from, Int3 to, BasisType basis, int strideOut) {
    std::vector<float> out(size_t(to.volume()) * size_t(strideOut), 0.0f);
    const Int3 n = from.dims;
    const Vec3d scale(double(n.x) / to.x, double(n.y) / to.y, double(n.z) / to.z);
    for (int k = 0; k < to.z; ++k)
        for (int j = 0; j < to.y; ++j)
            for (int i = 0; i < to.x; ++i) {
                const Vec3d q = (Vec3d(i, j, k) + Vec3d(0.5)) * scale - Vec3d(0.5);
                const Vec3d v = n == to ? sampleGrid(from, Vec3d(i, j, k), BasisType::Box) : sampleGrid(from, q, basis);
                size_t o = size_t(strideOut) * ((size_t(k) * to.y + size_t(j)) * to.x + size_t(i));
                out[o] = float(v.x), out[o + 1] = float(v.y), out[o + 2] = float(v.z);
            }
    return out;
}

}  // namespace volstyle::core

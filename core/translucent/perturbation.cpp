#include "core/translucent/perturbation.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/volume/resample.h"

namespace volstyle::core {

std::vector<FieldProblem> Perturbation::check() const {
    std::vector<FieldProblem> out;
    if (!(std::isfinite(amplitude) && amplitude >= 0 && amplitude <= 64)) out.push_back({"amplitude", "must be in [0, 64] voxels"});
    if (!(std::isfinite(frequency) && frequency > 0 && frequency <= 256)) out.push_back({"frequency", "must be in (0, 256]"});
    if (octaves < 1 || octaves > 6) out.push_back({"octaves", "must be in [1, 6]"});
    if (!(propertyAmplitude >= 0 && propertyAmplitude <= 1)) out.push_back({"property_amplitude", "must be in [0, 1]"});
    if (!std::isfinite(time)) out.push_back({"time", "must be finite"});
    return out;
}

std::vector<float> noiseTexels(uint32_t seed) {
    const int n = kNoiseSize;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> a(size_t(n) * n * n * 4);
    for (float& x : a) x = u(rng);
    // A 3-tap box blur per axis, periodic: hides the trilinear filter's creases (Sec. 3.4).
    auto at = [n](int i, int j, int k) { return ((size_t((k + n) % n) * n + size_t((j + n) % n)) * n + size_t((i + n) % n)) * 4; };
    for (int axis = 0; axis < 3; ++axis) {
        std::vector<float> b(a.size());
        for (int k = 0; k < n; ++k)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i)
                    for (int c = 0; c < 4; ++c) {
                        const int d[3] = {axis == 0, axis == 1, axis == 2};
                        b[at(i, j, k) + size_t(c)] = (a[at(i - d[0], j - d[1], k - d[2]) + size_t(c)] + a[at(i, j, k) + size_t(c)] +
                                                      a[at(i + d[0], j + d[1], k + d[2]) + size_t(c)]) / 3.0f;
                    }
        a.swap(b);
    }
    // Stretch each channel back to [0, 1] (the blur narrowed it).
    for (int c = 0; c < 4; ++c) {
        float lo = 1, hi = 0;
        for (size_t i = size_t(c); i < a.size(); i += 4) lo = std::min(lo, a[i]), hi = std::max(hi, a[i]);
        for (size_t i = size_t(c); i < a.size(); i += 4) a[i] = (a[i] - lo) / std::max(hi - lo, 1e-6f);
    }
    return a;
}

PerturbationField::PerturbationField(const Perturbation& p, Int3 dims) : m_p(p), m_texels(noiseTexels(p.seed)) {
    m_texelsPerVoxel = p.frequency / double(std::max({dims.x, dims.y, dims.z, 1}));
}

Vec3d PerturbationField::drift(int octave) { return Vec3d(0.31, 0.17, 0.23) * double(octave + 1); }

Vec3d PerturbationField::noise(const Vec3d& p, double& fourth) const {
    const int n = kNoiseSize;
    Vec3d sum;
    fourth = 0;
    double norm = 0;
    for (int o = 0; o < m_p.octaves; ++o) {
        const double w = std::ldexp(1.0, -o);
        // Texel coordinates of the sample (texel centres at i + 0.5, as the GPU's texture()).
        const Vec3d q = p * (m_texelsPerVoxel * std::ldexp(1.0, o)) + drift(o) * m_p.time - Vec3d(0.5);
        const Vec3d f0(std::floor(q.x), std::floor(q.y), std::floor(q.z));
        const Vec3d f = q - f0;
        double v[4] = {0, 0, 0, 0};
        for (int corner = 0; corner < 8; ++corner) {
            const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
            const double wt = (dx ? f.x : 1 - f.x) * (dy ? f.y : 1 - f.y) * (dz ? f.z : 1 - f.z);
            const int i = (int(f0.x) + dx) % n, j = (int(f0.y) + dy) % n, k = (int(f0.z) + dz) % n;
            const size_t idx = ((size_t((k + n) % n) * n + size_t((j + n) % n)) * n + size_t((i + n) % n)) * 4;
            for (int c = 0; c < 4; ++c) v[c] += wt * m_texels[idx + size_t(c)];
        }
        sum += Vec3d(2 * v[0] - 1, 2 * v[1] - 1, 2 * v[2] - 1) * w;
        fourth += (2 * v[3] - 1) * w;
        norm += w;
    }
    fourth /= norm;
    return sum / norm;
}

Vec3d PerturbationField::displacement(const Vec3d& p) const {
    double fourth = 0;
    return noise(p, fourth) * m_p.amplitude;
}

double PerturbationField::extinctionScale(const Vec3d& p) const {
    double fourth = 0;
    noise(p, fourth);
    return std::max(0.0, 1 + m_p.propertyAmplitude * fourth);
}

Volume perturbVolume(const Volume& volume, const Perturbation& p) {
    Volume out = volume;
    if (!p.active()) return out;
    const PerturbationField field(p, volume.dims());
    const Int3 n = volume.dims();
    const BrickLayout* bricks = volume.bricks();
    if (bricks) {
        // A sparse volume (issue #39): a voxel reads the medium up to `amplitude` voxels away along
        // each axis (and the trilinear corner past it), so the bricks within that reach of the
        // active ones can gain medium; the rest keep the background. Every voxel is written on its
        // own: tiles lose their shared slot.
        out.unshareTiles();
        out.activateBricksAround(int(std::ceil((p.amplitude + 1) / kBrickSide)));
    }
    const GridView sigma{volume.extinction(), n, 3, 0, bricks}, albedo{volume.albedo(), n, 3, 0, bricks},
        emission{volume.emission(), n, 3, 0, bricks};
    forEachActiveVoxel(out, [&](Int3 v, size_t stored) {
        const Vec3d at(v.x, v.y, v.z);
        const Vec3d q = at + field.displacement(at);
        const size_t idx = 3 * stored;
        const Vec3d s = sampleGrid(sigma, q, BasisType::Trilinear) * field.extinctionScale(at);
        for (int c = 0; c < 3; ++c) out.extinction()[idx + size_t(c)] = float(s[c]);
        if (volume.hasAlbedo()) {
            const Vec3d a = sampleGrid(albedo, q, BasisType::Trilinear);
            for (int c = 0; c < 3; ++c) out.albedo()[idx + size_t(c)] = float(a[c]);
        }
        if (volume.hasEmission()) {
            const Vec3d e = sampleGrid(emission, q, BasisType::Trilinear);
            for (int c = 0; c < 3; ++c) out.emission()[idx + size_t(c)] = float(e[c]);
        }
    });
    return out;
}

}  // namespace volstyle::core

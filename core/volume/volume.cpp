#include "core/volume/volume.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/base/errors.h"

namespace volstyle::core {

Volume::Volume(Int3 dims, const Mat4& worldFromIndex)
    : m_dims(dims), m_worldFromIndex(worldFromIndex), m_extinction(size_t(dims.volume()) * 3, 0.0f) {
    if (dims.x < 1 || dims.y < 1 || dims.z < 1) {
        std::ostringstream s;
        s << "a volume's dimensions must be at least 1x1x1, got " << dims;
        throw InvalidArgument(s.str());
    }
}

std::vector<float>& Volume::ensureAlbedo(float value) {
    if (m_albedo.empty()) m_albedo.assign(voxelCount() * 3, value);
    return m_albedo;
}

std::vector<float>& Volume::ensureEmission() {
    if (m_emission.empty()) m_emission.assign(voxelCount() * 3, 0.0f);
    return m_emission;
}

std::pair<Vec3d, Vec3d> Volume::worldBounds() const {
    Vec3d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (int c = 0; c < 8; ++c) {
        Vec3d p{(c & 1) ? m_dims.x - 0.5 : -0.5, (c & 2) ? m_dims.y - 0.5 : -0.5,
                (c & 4) ? m_dims.z - 0.5 : -0.5};
        Vec3d w = m_worldFromIndex.applyPoint(p);
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], w[a]), hi[a] = std::max(hi[a], w[a]);
    }
    return {lo, hi};
}

Vec3d Volume::voxelSize() const {
    return {length(m_worldFromIndex.applyVector({1, 0, 0})),
            length(m_worldFromIndex.applyVector({0, 1, 0})),
            length(m_worldFromIndex.applyVector({0, 0, 1}))};
}

bool Volume::isGrey(const std::vector<float>& rgb) {
    for (size_t i = 0; i + 2 < rgb.size(); i += 3)
        if (rgb[i] != rgb[i + 1] || rgb[i] != rgb[i + 2]) return false;
    return true;
}

std::pair<Vec3, Vec3> Volume::range(const std::vector<float>& rgb) {
    Vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (size_t i = 0; i + 2 < rgb.size(); i += 3)
        for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], rgb[i + c]), hi[c] = std::max(hi[c], rgb[i + c]);
    if (rgb.empty()) lo = hi = Vec3(0.0f);
    return {lo, hi};
}

InvalidValues findInvalidValues(const std::vector<float>& grid, int channels, float lo, float hi) {
    InvalidValues r;
    const size_t c = size_t(channels);
    for (size_t voxel = 0; voxel * c < grid.size(); ++voxel) {
        for (size_t k = 0; k < c; ++k) {
            const float v = grid[voxel * c + k];
            if (!(v >= lo && v <= hi)) {  // also catches NaN
                if (r.count++ == 0) r.firstVoxel = voxel, r.firstValue = v;
                break;
            }
        }
    }
    return r;
}

namespace {

void checkGrid(const Volume& v, const std::vector<float>& g, int channels, const char* name, float lo, float hi) {
    const size_t expected = v.voxelCount() * size_t(channels);
    if (g.size() != expected) {
        throw InvalidArgument(std::string("grid '") + name + "' has " + std::to_string(g.size()) +
                              " values, expected " + std::to_string(expected));
    }
    InvalidValues bad = findInvalidValues(g, channels, lo, hi);
    if (bad.count > 0) {
        const Int3 d = v.dims();
        const size_t n = bad.firstVoxel;
        std::ostringstream s;
        s << "grid '" << name << "' has " << bad.count << " voxel(s) with values outside [" << lo << ", ";
        if (hi == std::numeric_limits<float>::max()) s << "inf)";
        else s << hi << "]";
        s          << " or not finite; the first is " << bad.firstValue << " at voxel (" << n % size_t(d.x) << ", "
          << (n / size_t(d.x)) % size_t(d.y) << ", " << n / (size_t(d.x) * size_t(d.y)) << ")";
        throw InvalidArgument(s.str());
    }
}

}  // namespace

void Volume::validate(const VolumeLimits& limits) const {
    std::ostringstream s;
    if (m_dims.x < 1 || m_dims.y < 1 || m_dims.z < 1) {
        s << "the volume's dimensions " << m_dims << " are empty";
        throw InvalidArgument(s.str());
    }
    if (m_dims.volume() > limits.maxVoxels || m_dims.x > limits.maxSide ||
        m_dims.y > limits.maxSide || m_dims.z > limits.maxSide) {
        s << m_dims << " voxels is over the limit of " << limits.maxVoxels << " voxels (at most "
          << limits.maxSide << " on a side)";
        throw LimitExceeded(s.str());
    }
    (void)m_worldFromIndex.inverseAffine();  // throws when singular
    const float inf = std::numeric_limits<float>::max();
    checkGrid(*this, m_extinction, 3, "extinction", 0.0f, inf);
    if (hasAlbedo()) checkGrid(*this, m_albedo, 3, "albedo", 0.0f, 1.0f);
    if (hasEmission()) checkGrid(*this, m_emission, 3, "emission", 0.0f, inf);
    if (m_refractiveIndex) checkGrid(*this, *m_refractiveIndex, 1, "refractive_index", 1.0f, inf);
}

}  // namespace volstyle::core

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
        s << "Volume(): dimensions must be at least 1x1x1, got " << dims;
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

std::pair<Vec3, Vec3> Volume::range(const std::vector<float>& rgb) {
    Vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (size_t i = 0; i + 2 < rgb.size(); i += 3)
        for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], rgb[i + c]), hi[c] = std::max(hi[c], rgb[i + c]);
    if (rgb.empty()) lo = hi = Vec3(0.0f);
    return {lo, hi};
}

namespace {

void checkGrid(const std::vector<float>& g, size_t expected, const char* name, float lo, float hi) {
    if (g.size() != expected) {
        throw InvalidArgument(std::string("Volume::validate(): grid '") + name + "' has " +
                              std::to_string(g.size()) + " values, expected " + std::to_string(expected));
    }
    size_t bad = 0, first = 0;
    for (size_t i = 0; i < g.size(); ++i) {
        if (!(g[i] >= lo && g[i] <= hi)) {  // also catches NaN
            if (bad++ == 0) first = i;
        }
    }
    if (bad > 0) {
        std::ostringstream s;
        s << "Volume::validate(): grid '" << name << "' has " << bad << " value(s) outside ["
          << lo << ", " << hi << "] or not finite; the first is " << g[first] << " at voxel "
          << first / 3;
        throw InvalidArgument(s.str());
    }
}

}  // namespace

void Volume::validate(const VolumeLimits& limits) const {
    std::ostringstream s;
    if (m_dims.x < 1 || m_dims.y < 1 || m_dims.z < 1) {
        s << "Volume::validate(): dimensions " << m_dims << " are empty";
        throw InvalidArgument(s.str());
    }
    if (m_dims.volume() > limits.maxVoxels || m_dims.x > limits.maxSide ||
        m_dims.y > limits.maxSide || m_dims.z > limits.maxSide) {
        s << "Volume::validate(): " << m_dims << " voxels is over the limit of " << limits.maxVoxels
          << " voxels (at most " << limits.maxSide << " on a side)";
        throw LimitExceeded(s.str());
    }
    (void)m_worldFromIndex.inverseAffine();  // throws when singular
    const float inf = std::numeric_limits<float>::max();
    const size_t n = voxelCount() * 3;
    checkGrid(m_extinction, n, "extinction", 0.0f, inf);
    if (hasAlbedo()) checkGrid(m_albedo, n, "albedo", 0.0f, 1.0f);
    if (hasEmission()) checkGrid(m_emission, n, "emission", 0.0f, inf);
    if (m_refractiveIndex) {
        if (m_refractiveIndex->size() != voxelCount())
            throw InvalidArgument("Volume::validate(): grid 'refractive_index' has the wrong size");
        for (float v : *m_refractiveIndex)
            if (!(v >= 1.0f && v < inf))
                throw InvalidArgument("Volume::validate(): grid 'refractive_index' has a value < 1 or not finite");
    }
}

}  // namespace volstyle::core

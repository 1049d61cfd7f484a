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

const char* volumeStorageName(VolumeStorage storage) {
    return storage == VolumeStorage::Dense ? "dense" : storage == VolumeStorage::Sparse ? "sparse" : "auto";
}

VolumeStorage volumeStorageNamed(const std::string& name) {
    if (name == "auto") return VolumeStorage::Automatic;
    if (name == "dense") return VolumeStorage::Dense;
    if (name == "sparse") return VolumeStorage::Sparse;
    throw InvalidArgument("storage must be auto, dense or sparse, not '" + name + "'");
}

Volume::Volume(BrickLayout bricks, const Mat4& worldFromIndex)
    : m_dims(bricks.dims()), m_worldFromIndex(worldFromIndex), m_bricks(std::move(bricks)) {
    if (m_dims.x < 1 || m_dims.y < 1 || m_dims.z < 1) {
        std::ostringstream s;
        s << "a volume's dimensions must be at least 1x1x1, got " << m_dims;
        throw InvalidArgument(s.str());
    }
    m_extinction.assign(m_bricks->storedVoxels() * 3, 0.0f);
}

std::vector<float>& Volume::ensureAlbedo(float value) {
    // A sparse volume's inactive bricks read the background brick: albedo's default there.
    if (m_albedo.empty()) m_albedo.assign(storedVoxels() * 3, m_bricks ? kDefaultAlbedo : value);
    if (m_bricks && value != kDefaultAlbedo) std::fill(m_albedo.begin() + 3 * kBrickVoxels, m_albedo.end(), value);
    return m_albedo;
}

std::vector<float>& Volume::ensureEmission() {
    if (m_emission.empty()) m_emission.assign(storedVoxels() * 3, 0.0f);
    return m_emission;
}

size_t Volume::activeVoxels() const {
    if (!m_bricks) return voxelCount();
    size_t n = 0;
    m_bricks->forEachActiveBrick([&](Int3 b, uint32_t) {
        const Int3 f = m_bricks->firstVoxel(b);
        size_t c = 1;
        for (int a = 0; a < 3; ++a) c *= size_t(std::min(f[a] + kBrickSide, m_dims[a]) - std::max(f[a], 0));
        n += c;
    });
    return n;
}

uint32_t Volume::activateBrick(Int3 b) {
    if (!m_bricks) throw InternalError("activateBrick on a dense volume");
    const uint32_t before = m_bricks->slotOf(b);
    const uint32_t slot = m_bricks->activate(b);
    if (slot != before) {
        // The new slot starts as a copy of what the brick read: the background or its tile.
        auto grow = [&](std::vector<float>& g, size_t channels) {
            if (g.empty()) return;
            const size_t n = channels * kBrickVoxels, end = g.size();
            g.resize(end + n);
            std::copy_n(g.begin() + ptrdiff_t(before * n), n, g.begin() + ptrdiff_t(end));
        };
        grow(m_extinction, 3), grow(m_albedo, 3), grow(m_emission, 3);
        if (m_refractiveIndex) grow(*m_refractiveIndex, 1);
    }
    return slot;
}

void Volume::unshareTiles() {
    if (!m_bricks || !m_bricks->hasSharedSlots()) return;
    std::vector<Int3> tiled;
    m_bricks->forEachActiveBrick([&](Int3 b, uint32_t slot) {
        if (m_bricks->isShared(slot)) tiled.push_back(b);
    });
    for (const Int3& b : tiled) activateBrick(b);
}

void Volume::activateBricksAround(int radius) {
    if (!m_bricks || radius <= 0) return;
    const BrickLayout active = *m_bricks;
    active.forEachActiveBrick([&](Int3 b, uint32_t) {
        active.forEachBrickAround(b, radius, [&](Int3 n) {
            if (!m_bricks->isActive(n)) activateBrick(n);
        });
    });
}

Int3 Volume::voxelOfStored(size_t stored) const {
    if (!m_bricks) {
        const size_t nx = size_t(m_dims.x), ny = size_t(m_dims.y);
        return {int(stored % nx), int((stored / nx) % ny), int(stored / (nx * ny))};
    }
    const size_t slot = stored / kBrickVoxels, local = stored % kBrickVoxels;
    if (slot == 0) return {-1, -1, -1};
    const Int3 f = m_bricks->firstVoxel(m_bricks->brickOfSlot(slot));
    return {f.x + int(local % kBrickSide), f.y + int((local / kBrickSide) % kBrickSide), f.z + int(local / (kBrickSide * kBrickSide))};
}

namespace {

/// Copies every voxel of the box from one volume's grid to another's (either layout).
void copyBox(const Volume& from, const std::vector<float>& src, const Volume& to, std::vector<float>& dst, int channels) {
    if (src.empty()) return;
    const Int3 d = from.dims();
    for (int k = 0; k < d.z; ++k)
        for (int j = 0; j < d.y; ++j)
            for (int i = 0; i < d.x; ++i) {
                const size_t a = from.index(i, j, k), b = to.index(i, j, k);
                for (int c = 0; c < channels; ++c) dst[size_t(channels) * b + size_t(c)] = src[size_t(channels) * a + size_t(c)];
            }
}

template <typename F>
void forEachGrid(const Volume& from, Volume& to, F&& f) {
    f(from.extinction(), to.extinction(), 3);
    if (from.hasAlbedo()) f(from.albedo(), to.ensureAlbedo(), 3);
    if (from.hasEmission()) f(from.emission(), to.ensureEmission(), 3);
    if (from.refractiveIndex()) {
        to.refractiveIndex() = std::vector<float>(to.storedVoxels(), 1.0f);
        f(*from.refractiveIndex(), *to.refractiveIndex(), 1);
    }
}

}  // namespace

Volume Volume::toDense(const VolumeLimits& limits) const {
    if (!m_bricks) return *this;
    if (m_dims.volume() > limits.maxVoxels || std::max({m_dims.x, m_dims.y, m_dims.z}) > limits.maxSide) {
        std::ostringstream s;
        s << "a dense copy of this " << m_dims << " volume is over the limit of " << limits.maxVoxels << " voxels (at most "
          << limits.maxSide << " on a side)";
        throw LimitExceeded(s.str());
    }
    Volume out(m_dims, m_worldFromIndex);
    forEachGrid(*this, out, [&](const std::vector<float>& src, std::vector<float>& dst, int c) { copyBox(*this, src, out, dst, c); });
    out.m_vdbSource = m_vdbSource;
    return out;
}

Volume Volume::toSparse(Int3 offset) const {
    if (m_bricks) return *this;
    BrickLayout layout(m_dims, offset);
    // A brick is active when any of its voxels differs from the background in any grid.
    const float* grids[3] = {m_extinction.data(), hasAlbedo() ? m_albedo.data() : nullptr, hasEmission() ? m_emission.data() : nullptr};
    const float background[3] = {0.0f, kDefaultAlbedo, 0.0f};
    for (int k = 0; k < m_dims.z; ++k)
        for (int j = 0; j < m_dims.y; ++j)
            for (int i = 0; i < m_dims.x; ++i) {
                const size_t n = index(i, j, k);
                bool differs = m_refractiveIndex && (*m_refractiveIndex)[n] != 1.0f;
                for (int g = 0; g < 3 && !differs; ++g)
                    if (grids[g])
                        for (int c = 0; c < 3; ++c) differs = differs || grids[g][3 * n + size_t(c)] != background[g];
                if (differs) layout.activate(layout.brickOf({i, j, k}));
            }
    Volume out(std::move(layout), m_worldFromIndex);
    forEachGrid(*this, out, [&](const std::vector<float>& src, std::vector<float>& dst, int c) { copyBox(*this, src, out, dst, c); });
    out.m_vdbSource = m_vdbSource;
    return out;
}

std::vector<float> gridOnBricks(const Volume& from, const std::vector<float>& grid, int channels, const BrickLayout& bricks,
                                float background) {
    const size_t block = size_t(channels) * kBrickVoxels;
    if (!(from.dims() == bricks.dims())) throw InternalError("gridOnBricks: the layout is not over the volume's box");
    if (grid.size() != size_t(channels) * from.storedVoxels()) throw InternalError("gridOnBricks: the grid does not match its volume");
    // Every slot starts as the background (a brick's voxels outside the box keep it), then each
    // voxel of an active brick reads the source's value.
    std::vector<float> brickOfBackground(block, background);
    if (from.isSparse()) std::copy_n(grid.begin(), block, brickOfBackground.begin());
    std::vector<float> out(size_t(channels) * bricks.storedVoxels());
    for (size_t slot = 0; slot < bricks.slots(); ++slot) std::copy(brickOfBackground.begin(), brickOfBackground.end(), out.begin() + ptrdiff_t(slot * block));
    bricks.forEachStoredVoxel([&](Int3 p, size_t stored) {
        const size_t src = from.index(p.x, p.y, p.z);
        for (int c = 0; c < channels; ++c) out[size_t(channels) * stored + size_t(c)] = grid[size_t(channels) * src + size_t(c)];
    });
    return out;
}

Volume Volume::onBricks(const BrickLayout& bricks) const {
    Volume out(bricks, m_worldFromIndex);
    out.m_extinction = gridOnBricks(*this, m_extinction, 3, bricks, 0.0f);
    if (hasAlbedo()) out.m_albedo = gridOnBricks(*this, m_albedo, 3, bricks, kDefaultAlbedo);
    if (hasEmission()) out.m_emission = gridOnBricks(*this, m_emission, 3, bricks, 0.0f);
    if (m_refractiveIndex) out.m_refractiveIndex = gridOnBricks(*this, *m_refractiveIndex, 1, bricks, 1.0f);
    out.m_vdbSource = m_vdbSource;
    return out;
}

void requireDense(const Volume& volume, const char* what) {
    if (!volume.isSparse()) return;
    std::ostringstream s;
    s << what << " works on dense volumes only, and this " << volume.dims() << " volume is sparse (" << volume.activeVoxels()
      << " active voxels); load it with dense storage (e.g. --storage dense) if it fits";
    throw InvalidArgument(s.str());
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
    const size_t expected = v.storedVoxels() * size_t(channels);
    if (g.size() != expected) {
        throw InvalidArgument(std::string("grid '") + name + "' has " + std::to_string(g.size()) +
                              " values, expected " + std::to_string(expected));
    }
    InvalidValues bad = findInvalidValues(g, channels, lo, hi);
    if (bad.count > 0) {
        const Int3 at = v.voxelOfStored(bad.firstVoxel);
        std::ostringstream s;
        s << "grid '" << name << "' has " << bad.count << " voxel(s) with values outside [" << lo << ", ";
        if (hi == std::numeric_limits<float>::max()) s << "inf)";
        else s << hi << "]";
        s << " or not finite; the first is " << bad.firstValue;
        if (at.x < 0) s << " in the background brick";
        else s << " at voxel (" << at.x << ", " << at.y << ", " << at.z << ")";
        throw InvalidArgument(s.str());
    }
}

}  // namespace

void checkSparseLimits(Int3 dims, size_t activeBricks, size_t storedSlots, int rgbGrids, const VolumeLimits& limits) {
    const int64_t voxels = int64_t(activeBricks) * kBrickVoxels;
    const int64_t bytes = int64_t(storedSlots) * kBrickVoxels * 3 * int64_t(sizeof(float)) * rgbGrids;
    std::ostringstream s;
    if (std::max({dims.x, dims.y, dims.z}) > limits.maxSparseSide) {
        s << "the " << dims << " box is over the limit of " << limits.maxSparseSide << " voxels on a side";
        throw LimitExceeded(s.str());
    }
    if (voxels > limits.maxActiveVoxels || bytes > limits.maxSparseBytes) {
        s << "the " << dims << " volume has " << activeBricks << " active bricks of " << kBrickSide << "^3 (" << voxels
          << " voxels, stored in " << storedSlots << " bricks: " << (bytes >> 20) << " MiB for " << rgbGrids
          << " RGB grid(s)), over the limit of " << limits.maxActiveVoxels
          << " active voxels and " << (limits.maxSparseBytes >> 20) << " MiB";
        throw LimitExceeded(s.str());
    }
}

void Volume::validate(const VolumeLimits& limits) const {
    std::ostringstream s;
    if (m_dims.x < 1 || m_dims.y < 1 || m_dims.z < 1) {
        s << "the volume's dimensions " << m_dims << " are empty";
        throw InvalidArgument(s.str());
    }
    if (m_bricks) {
        checkSparseLimits(m_dims, m_bricks->activeBricks(), m_bricks->slots(), 1 + int(hasAlbedo()) + int(hasEmission()), limits);
        if (!(m_bricks->dims() == m_dims)) throw InternalError("a sparse volume's bricks cover another box");
        // Empty-space skipping takes an inactive brick to be empty.
        auto zeroBackground = [&](const std::vector<float>& g, const char* name) {
            if (!g.empty() && std::any_of(g.begin(), g.begin() + 3 * kBrickVoxels, [](float v) { return v != 0.0f; }))
                throw InvalidArgument(std::string("a sparse volume's ") + name + " must be 0 outside its active voxels (the grid's background is not)");
        };
        if (m_extinction.size() >= size_t(3 * kBrickVoxels)) zeroBackground(m_extinction, "extinction");
        if (m_emission.size() >= size_t(3 * kBrickVoxels)) zeroBackground(m_emission, "emission");
    } else if (m_dims.volume() > limits.maxVoxels || m_dims.x > limits.maxSide ||
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

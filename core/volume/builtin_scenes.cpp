#include "core/volume/builtin_scenes.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/base/errors.h"
#include "core/base/parallel.h"
#include "core/volume/noise.h"

namespace volstyle::core {
namespace {

double smoothstep(double a, double b, double x) {
    double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
    return t * t * (3 - 2 * t);
}

/// Wyvill's soft-object kernel: 1 at the centre, 0 at radius, C1 smooth.
double blobKernel(double distance, double radius) {
    double q = distance / radius;
    if (q >= 1) return 0;
    double s = 1 - q * q;
    return s * s * s;
}

struct VoxelProperties {
    Vec3 extinction, albedo, emission;
};
using SceneFunction = std::function<VoxelProperties(const Vec3d& world)>;

/// Runs body(k) for every slice k in [0, n) on the machine's cores (core/base/parallel.h).
template <typename Body>
void forEachSlice(int n, const Body& body) {
    forEachChunk(size_t(std::max(n, 0)), 1, [&](size_t, size_t k, size_t) { body(int(k)); });
}

/// Evaluates `f` at every voxel centre, slices in parallel.
Volume sample(int resolution, bool hasEmission, const SceneFunction& f) {
    Int3 dims{resolution, resolution, resolution};
    Volume v(dims, unitBoxWorldFromIndex(dims));
    auto& ext = v.extinction();
    auto& alb = v.ensureAlbedo();
    std::vector<float>* emi = hasEmission ? &v.ensureEmission() : nullptr;
    forEachSlice(resolution, [&](int k) {
        for (int j = 0; j < resolution; ++j)
            for (int i = 0; i < resolution; ++i) {
                VoxelProperties p = f(v.worldFromIndex().applyPoint({double(i), double(j), double(k)}));
                size_t n = 3 * v.index(i, j, k);
                for (int c = 0; c < 3; ++c) {
                    ext[n + c] = p.extinction[c];
                    alb[n + c] = p.albedo[c];
                    if (emi) (*emi)[n + c] = p.emission[c];
                }
            }
    });
    return v;
}

/// Cumulus: blended implicit blobs — a broad flat base, a middle layer and towers — whose lookup
/// position is displaced by multi-octave noise, with billowy (cauliflower) noise on the surface
/// and a flat bottom (Kniss et al. Sec. 3.4: implicit shapes perturbed by noise).
Volume makeCloud(int res) {
    struct Blob {
        Vec3d c;
        double r;
    };
    const std::vector<Blob> blobs = {
        // base layer, wide and low
        {{-0.62, -0.38, 0.05}, 0.34}, {{-0.25, -0.40, -0.10}, 0.40}, {{0.15, -0.40, 0.08}, 0.42},
        {{0.55, -0.38, -0.05}, 0.36}, {{-0.05, -0.38, 0.38}, 0.32}, {{0.05, -0.40, -0.40}, 0.32},
        // middle
        {{-0.35, -0.08, 0.02}, 0.33}, {{0.05, -0.02, -0.05}, 0.38}, {{0.40, -0.10, 0.08}, 0.30},
        // towers
        {{-0.10, 0.28, 0.02}, 0.28}, {{0.18, 0.32, -0.05}, 0.25}, {{0.02, 0.55, 0.0}, 0.20},
    };
    PerlinNoise noise(7);
    const double sigmaMax = 40.0;  // per world unit: optical depth ~40 across the core
    // Exact shortcuts (most of the box is empty; they halve a 128³ build): improved Perlin noise,
    // and so fbm, stays within ±kNoiseBound, so the lookup q moves at most kShift from p, and
    // billows and wisps add at most kDetail to the field.
    constexpr double kNoiseBound = 1.1, kShift = 0.10 * kNoiseBound * 1.7320508075688772, kDetail = 0.16 + 0.05 * kNoiseBound;
    const VoxelProperties empty{Vec3(0.0f), Vec3(1.0f), Vec3(0.0f)};
    return sample(res, false, [&](const Vec3d& p) {
        double base = smoothstep(-0.66, -0.56, p.y);  // flat bottom
        if (base <= 0) return empty;
        bool nearBlob = false;  // the field is 0 unless q lies inside some blob
        for (const auto& b : blobs) nearBlob = nearBlob || length(p - b.c) < b.r + kShift;
        if (!nearBlob) return empty;
        Vec3d q = p + noise.fbm3(p * 2.2, 3) * 0.10;  // large-scale lumpiness
        double field = 0;
        for (const auto& b : blobs) field += blobKernel(length(q - b.c), b.r);
        if (field + kDetail <= 0.22) return empty;  // below smoothstep's lower edge whatever the detail
        // Billows: 1 - |noise| has rounded crests and sharp creases, like cauliflower tops.
        double billow = 1.0 - 2.0 * std::abs(noise.fbm(q * 5.5 + Vec3d(3.1, 0, 0), 3));
        double wisps = noise.fbm(p * 14.0, 2);
        double density = smoothstep(0.22, 0.5, field + 0.16 * billow + 0.05 * wisps) * base;
        return VoxelProperties{Vec3(float(sigmaMax * density)), Vec3(1.0f), Vec3(0.0f)};
    });
}

/// A smoke column rising from a source near the floor: its radius grows and its density falls
/// with height, its axis wanders, and turbulent displacement and wispy breakup grow as it rises.
Volume makePlume(int res) {
    PerlinNoise noise(11);
    return sample(res, false, [&](const Vec3d& p) {
        double h = std::clamp((p.y + 0.9) / 1.8, 0.0, 1.0);  // 0 at the source, 1 at the top
        Vec3d q = p + noise.fbm3(p * 2.5 + Vec3d(0, -2.0 * h, 0), 4) * (0.02 + 0.30 * h * h);
        double cx = 0.30 * h * noise.fbm({0.3, q.y * 1.1, 0.7}, 2);
        double cz = 0.30 * h * noise.fbm({5.1, q.y * 1.1, 2.3}, 2);
        double radius = 0.06 + 0.42 * std::pow(h, 0.9);
        double r = std::hypot(q.x - cx, q.z - cz);
        double column = 1 - smoothstep(0.35 * radius, radius, r);
        double top = 1 - smoothstep(0.45, 0.92, q.y + 0.15 * noise.fbm(q * 3.0, 2));
        double bottom = smoothstep(-0.95, -0.85, p.y);
        double wisps = std::clamp(0.55 + 1.2 * noise.fbm(q * 7.0 + Vec3d(0, -3.0 * h, 0), 4), 0.0, 1.0);
        double density = column * top * bottom * wisps * (1.0 - 0.7 * h);
        return VoxelProperties{Vec3(float(14.0 * density)), Vec3(0.7f), Vec3(0.0f)};
    });
}

Volume makeSphere(int res) {
    return sample(res, false, [](const Vec3d& p) {
        double density = 1 - smoothstep(0.3, 0.8, length(p));
        return VoxelProperties{Vec3(float(8.0 * density)), Vec3(0.9f), Vec3(0.0f)};
    });
}

Volume makeCube(int res) {
    return sample(res, false, [](const Vec3d&) {
        return VoxelProperties{Vec3(2.0f), Vec3(0.8f), Vec3(0.0f)};
    });
}

}  // namespace

const std::vector<BuiltinSceneInfo>& builtinScenes() {
    static const std::vector<BuiltinSceneInfo> scenes = {
        {"cloud", "a cumulus cloud: noise-perturbed blended blobs with a flat base"},
        {"plume", "a rising, spreading smoke column with turbulent detail"},
        {"sphere", "a sphere of smoke with a smooth falloff"},
        {"cube", "a cube of constant extinction (closed-form tests)"},
    };
    return scenes;
}

void addGlassSphere(Volume& volume, const GlassSphere& g) {
    const auto [lo, hi] = volume.worldBounds();
    const Vec3d centre = (lo + hi) * 0.5;
    const Vec3d voxel = volume.voxelSize();
    const double edge = std::max(g.edgeVoxels, 1e-3) * std::min({voxel.x, voxel.y, voxel.z});
    const PerlinNoise noise(g.seed);
    const Int3 n = volume.dims();
    auto indexAt = [&](Int3 v) {
        const Vec3d x = volume.worldFromIndex().applyPoint({double(v.x), double(v.y), double(v.z)});
        // 1 − smoothstep across [R − edge/2, R + edge/2]: the glass's share of the voxel.
        const double inside = 1 - smoothstep(g.radius - 0.5 * edge, g.radius + 0.5 * edge, length(x - centre));
        const double glass = std::max(1.0, g.index + g.noise * noise(x * g.noiseFrequency));
        return float(1 + (glass - 1) * inside);
    };
    if (volume.isSparse()) {
        // Issue #39: the bricks the glass can reach (a brick's centre within the sphere, its edge
        // and the brick's half-diagonal) become active; the rest keep index 1, the background.
        volume.unshareTiles();
        const BrickLayout layout = *volume.bricks();
        const Vec3d half = voxel * (0.5 * kBrickSide);
        const double reach = g.radius + 0.5 * edge + length(half);
        for (int z = 0; z < layout.brickDims().z; ++z)
            for (int y = 0; y < layout.brickDims().y; ++y)
                for (int x = 0; x < layout.brickDims().x; ++x) {
                    const Int3 f = layout.firstVoxel({x, y, z});
                    const Vec3d mid(f.x + 0.5 * (kBrickSide - 1), f.y + 0.5 * (kBrickSide - 1), f.z + 0.5 * (kBrickSide - 1));
                    if (length(volume.worldFromIndex().applyPoint(mid) - centre) <= reach && !layout.isActive({x, y, z})) volume.activateBrick({x, y, z});
                }
        std::vector<float> index(volume.storedVoxels(), 1.0f);
        forEachActiveVoxel(volume, [&](Int3 v, size_t stored) { index[stored] = indexAt(v); });
        volume.refractiveIndex() = std::move(index);
        return;
    }
    std::vector<float> index(volume.voxelCount());
    forEachSlice(n.z, [&](int k) {
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) index[volume.index(i, j, k)] = indexAt({i, j, k});
    });
    volume.refractiveIndex() = std::move(index);
}

Mat4 unitBoxWorldFromIndex(Int3 dims) {
    double h = 2.0 / std::max({dims.x, dims.y, dims.z});
    Vec3d origin{-0.5 * dims.x * h + 0.5 * h, -0.5 * dims.y * h + 0.5 * h, -0.5 * dims.z * h + 0.5 * h};
    return Mat4::translate(origin) * Mat4::scale(Vec3d(h));
}

Volume makeBuiltinScene(const std::string& name, int resolution) {
    if (resolution < kMinSceneResolution || resolution > kMaxSceneResolution) {
        throw InvalidArgument("resolution must be in [" +
                              std::to_string(kMinSceneResolution) + ", " +
                              std::to_string(kMaxSceneResolution) + "], got " + std::to_string(resolution));
    }
    if (name == "cloud") return makeCloud(resolution);
    if (name == "plume") return makePlume(resolution);
    if (name == "sphere") return makeSphere(resolution);
    if (name == "cube") return makeCube(resolution);
    std::string known;
    for (const auto& s : builtinScenes()) known += (known.empty() ? "" : ", ") + s.name;
    throw InvalidArgument("unknown scene '" + name + "'; built-in scenes: " + known);
}

}  // namespace volstyle::core

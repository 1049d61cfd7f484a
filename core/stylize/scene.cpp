#include "core/stylize/scene.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "core/base/errors.h"

namespace volstyle::core {

namespace {

/// The first problem of a TF (its fields named below `path`), anchors checked against `occluders`.
void validateTransferFunction(const TransferFunction& tf, const std::string& path, const std::vector<Occluder>& occluders) {
    if (!tf.layers.empty()) {
        if (tf.width < 1 || tf.width > 1024 || tf.height < 1 || tf.height > 1024)
            throw InvalidArgument(path + "/size: must be 1–1024 texels a side");
        for (size_t l = 0; l < tf.layers.size(); ++l)
            for (size_t c = 0; c < tf.layers[l].constraints.size(); ++c) {
                const auto& anchor = tf.layers[l].constraints[c].anchor;
                if (!anchor) continue;
                const std::string at = path + "/layers/" + std::to_string(l) + "/constraints/" + std::to_string(c) + "/anchor";
                for (int k = 0; k < 3; ++k)
                    if (!(std::abs(anchor->position[k]) <= 1e9)) throw InvalidArgument(at + "/position: must be finite (|x| <= 1e9)");
                if (!anchor->follow.empty() &&
                    std::none_of(occluders.begin(), occluders.end(), [&](const Occluder& o) { return o.name == anchor->follow; }))
                    throw InvalidArgument(at + "/follow: no occluder is named '" + anchor->follow + "'");
            }
    } else if (!tf.image || tf.image->empty()) {
        throw InvalidArgument(path + "/image: the image is empty");
    }
    if (tf.image && (tf.image->width > 4096 || tf.image->height > 4096)) throw InvalidArgument(path + "/image: at most 4096 texels a side");
    if (!(tf.depthFar > tf.depthNear) || !std::isfinite(tf.depthNear) || !std::isfinite(tf.depthFar))
        throw InvalidArgument(path + "/depth_range: must be two finite numbers, the second larger");
    if (tf.image && tf.layers.empty())  // an uploaded image (compiled ones are checked as they are made)
        for (float v : tf.image->rgba)
            if (!std::isfinite(v) || v < 0) throw InvalidArgument(path + "/image: values must be finite and >= 0");
}

/// The TF's texel grid: its layers' size, or its image's.
std::pair<int, int> tfSize(const TransferFunction& tf) {
    if (!tf.layers.empty()) return {tf.width, tf.height};
    return tf.image ? std::pair{tf.image->width, tf.image->height} : std::pair{0, 0};
}

/// Keys by increasing time, cameras of one size, and TFs that blend texel by texel: all keys or
/// none have one, all of one size, mode and depth range.
void validateKeyframes(const std::vector<StylizerKeyframe>& keys, const std::vector<Occluder>& occluders) {
    if (keys.size() > kMaxKeyframes) throw InvalidArgument("/keyframes: at most " + std::to_string(kMaxKeyframes) + " keys");
    for (size_t i = 0; i < keys.size(); ++i) {
        const std::string at = "/keyframes/" + std::to_string(i);
        const StylizerKeyframe& k = keys[i];
        if (!(std::abs(k.time) <= 1e9)) throw InvalidArgument(at + "/time: must be finite (|t| <= 1e9)");
        if (i > 0 && !(k.time > keys[i - 1].time)) throw InvalidArgument(at + "/time: keys go by increasing time");
        try {
            k.camera.validate();
        } catch (const InvalidArgument& e) {
            throw InvalidArgument(at + "/camera: " + e.what());
        }
        if (k.camera.width != keys[0].camera.width || k.camera.height != keys[0].camera.height)
            throw InvalidArgument(at + "/camera: every key's camera has the first one's size (" + std::to_string(keys[0].camera.width) + "×" +
                                  std::to_string(keys[0].camera.height) + ")");
        if (k.transferFunction.has_value() != keys[0].transferFunction.has_value())
            throw InvalidArgument(at + "/transfer_function: every key has a TF, or none does");
        if (!k.transferFunction) continue;
        const TransferFunction& tf = *k.transferFunction;
        validateTransferFunction(tf, at + "/transfer_function", occluders);
        const TransferFunction& first = *keys[0].transferFunction;
        if (tfSize(tf) != tfSize(first) || tf.mode != first.mode || tf.depthNear != first.depthNear || tf.depthFar != first.depthFar)
            throw InvalidArgument(at + "/transfer_function: keys blend their TFs texel by texel, so every key's has the first one's "
                                       "size, mode and depth_range");
    }
}

}  // namespace

std::vector<TransferFunction*> StylizerScene::transferFunctions() {
    std::vector<TransferFunction*> out;
    if (transferFunction) out.push_back(&*transferFunction);
    for (StylizerKeyframe& k : keyframes)
        if (k.transferFunction) out.push_back(&*k.transferFunction);
    return out;
}

std::vector<const TransferFunction*> StylizerScene::transferFunctions() const {
    std::vector<const TransferFunction*> out;
    if (transferFunction) out.push_back(&*transferFunction);
    for (const StylizerKeyframe& k : keyframes)
        if (k.transferFunction) out.push_back(&*k.transferFunction);
    return out;
}

void StylizerScene::checkTfCompileWork() const {
    // What compiling every TF costs: texels times (diffusion layers + 1), all TFs together.
    double work = 0;
    for (const TransferFunction* tf : transferFunctions()) {
        if (tf->layers.empty()) continue;
        double layers = 1;
        for (const TfLayer& l : tf->layers) layers += l.kind == TfLayerKind::Diffusion ? 1 : 0;
        work += double(tf->width) * tf->height * layers;
    }
    if (work > kMaxTfCompileWork)
        throw InvalidArgument("/transfer_function: compiling every TF (the scene's and the key frames') would cost " +
                              std::to_string(int64_t(work)) + " texel-layers, over the limit of " + std::to_string(int64_t(kMaxTfCompileWork)) +
                              " (about 8 s): use smaller sizes, fewer diffusion layers or fewer keys with TFs");
}

std::vector<FieldProblem> Manipulation::check() const {
    std::vector<FieldProblem> out;
    const auto whole = [](double v) { return std::to_string(static_cast<long long>(v)); };
    if (closingRadius < 0 || closingRadius > kMaxClosingRadiusPx)
        out.push_back({"closing/radius_px", "must be in [0, " + whole(kMaxClosingRadiusPx) + "]"});
    if (!(dilationLength >= 0 && dilationLength <= kMaxDilationLength))
        out.push_back({"dilation/length", "must be in [0, " + whole(kMaxDilationLength) + "]"});
    if (erosionPx < 0 || erosionPx > kMaxErosionPx) out.push_back({"dilation/erosion_px", "must be in [0, " + whole(kMaxErosionPx) + "]"});
    if (!(holeProbability >= 0 && holeProbability <= 1)) out.push_back({"holes/probability", "must be in [0, 1]"});
    if (!(holeFrequency > 0 && holeFrequency <= kMaxHoleFrequency))
        out.push_back({"holes/frequency", "must be in (0, " + whole(kMaxHoleFrequency) + "]"});
    if (!(std::abs(holeSpeed) <= kMaxHoleSpeed))
        out.push_back({"holes/speed", "must be in [-" + whole(kMaxHoleSpeed) + ", " + whole(kMaxHoleSpeed) + "]"});
    if (holeOctaves < kMinHoleOctaves || holeOctaves > kMaxHoleOctaves)
        out.push_back({"holes/octaves", "must be in [" + whole(kMinHoleOctaves) + ", " + whole(kMaxHoleOctaves) + "]"});
    if (!(holePersistence > 0 && holePersistence <= 1)) out.push_back({"holes/persistence", "must be in (0, 1]"});
    return out;
}

std::vector<FieldProblem> StylizerLight::check() const {
    std::vector<FieldProblem> out;
    const auto finite = [](const Vec3d& v, double bound) { return std::abs(v.x) <= bound && std::abs(v.y) <= bound && std::abs(v.z) <= bound; };
    if (!finite(direction, 1e9)) out.push_back({"direction", "must be within ±1e9 (only its direction counts)"});
    else if (!(length(direction) > 0)) out.push_back({"direction", "must not be zero"});
    if (!finite(position, 1e9)) out.push_back({"position", "must be finite (|x| <= 1e9)"});
    if (type == StylizerLightType::Spot && !(coneDeg > 0 && coneDeg <= 150)) out.push_back({"cone_deg", "must be in (0, 150]"});
    // Bounds that keep every product in float range (SPEC §5: nothing may become NaN or Inf).
    if (!(irradiance.x >= 0 && irradiance.y >= 0 && irradiance.z >= 0 && finite(irradiance, 1e6)))
        out.push_back({"irradiance", "must be in [0, 1e6]"});
    if (shadowMapSize < 512 || shadowMapSize > 4096) out.push_back({"shadow_map_size", "must be in [512, 4096]"});
    return out;
}

std::vector<FieldProblem> HomogeneousMedium::check() const {
    std::vector<FieldProblem> out;
    if (!(extinction >= 0 && extinction <= 1e6)) out.push_back({"extinction", "must be in [0, 1e6]"});
    if (!(albedo >= 0 && albedo <= 1)) out.push_back({"albedo", "must be in [0, 1]"});
    return out;
}

void StylizerScene::validate() const {
    for (const Occluder& o : occluders) {
        try {
            if (!o.mesh) throw InvalidArgument("has no mesh");
            o.mesh->validate();
        } catch (const InvalidArgument& e) {
            throw InvalidArgument("occluder '" + o.name + "': " + e.what());
        }
        for (int row = 0; row < 4; ++row)
            for (int c = 0; c < 4; ++c)
                if (!(std::abs(o.worldFromObject(row, c)) <= 1e9))
                    throw InvalidArgument("occluder '" + o.name + "': transform entries must be within ±1e9");
        if (const auto problems = o.manipulation.check(); !problems.empty())
            throw InvalidArgument("occluder '" + o.name + "': manipulation " + problems.front().field + " " + problems.front().message);
    }
    for (const FieldProblem& p : light.check()) throw InvalidArgument("/light/" + p.field + ": " + p.message);
    if (!(std::abs(time) <= 1e9)) throw InvalidArgument("/time: must be finite (|t| <= 1e9)");
    for (const FieldProblem& p : medium.check()) throw InvalidArgument("/medium/" + p.field + ": " + p.message);
    for (int c = 0; c < 3; ++c)
        if (!(background[c] >= 0 && background[c] <= 1e6)) throw InvalidArgument("/background: must be in [0, 1e6]");
    camera.validate();
    if (transferFunction) validateTransferFunction(*transferFunction, "/transfer_function", occluders);
    if (volume) {
        const StylizerVolume& v = *volume;
        for (int k = 0; k < 3; ++k)
            if (!(v.hi[k] > v.lo[k]) || !(std::abs(v.lo[k]) <= 1e9 && std::abs(v.hi[k]) <= 1e9))
                throw InvalidArgument("/volume/box: must be [[x0, y0, z0], [x1, y1, z1]], finite, with x1 > x0, y1 > y0, z1 > z0");
        if (!(v.extinctionScale >= 0 && v.extinctionScale <= 1e6)) throw InvalidArgument("/volume/extinction_scale: must be in [0, 1e6]");
        if (v.steps < 1 || v.steps > 4096) throw InvalidArgument("/volume/steps: must be in [1, 4096]");
    }
    validateKeyframes(keyframes, occluders);
    checkTfCompileWork();
}

void StylizeSettings::validate() const {
    if (steps < 1 || steps > 4096) throw InvalidArgument("/steps: must be in [1, 4096]");
    if (spotSteps < 1 || spotSteps > 4096) throw InvalidArgument("/spot_steps: must be in [1, 4096]");
}

namespace {

/// Uniform in [0, 1) from raw mt19937 outputs (std distributions are not portable).
struct Random {
    std::mt19937 rng;
    explicit Random(uint32_t seed) : rng(seed) {}
    double operator()() { return double(rng()) / 4294967296.0; }
};

void addQuad(Mesh& m, Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    const Vec3 n = normalize(cross(b - a, d - a));
    const auto base = uint32_t(m.positions.size());
    for (const Vec3& p : {a, b, c, d}) m.positions.push_back(p), m.normals.push_back(n);
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
}

/// An n-sided prism from y0 to y1 around (x, z), its radius tapering from r0 to r1.
void addTrunk(Mesh& m, double x, double z, double y0, double y1, double r0, double r1, int sides) {
    for (int s = 0; s < sides; ++s) {
        const double a0 = 2 * std::numbers::pi * s / sides, a1 = 2 * std::numbers::pi * (s + 1) / sides;
        auto at = [&](double a, double r, double y) { return Vec3(float(x + r * std::cos(a)), float(y), float(z + r * std::sin(a))); };
        addQuad(m, at(a0, r0, y0), at(a0, r1, y1), at(a1, r1, y1), at(a1, r0, y0));
    }
}

/// Leaves: small quads at random orientations inside an ellipsoid (a canopy that lets light
/// through in patches, the paper's foliage).
void addCanopy(Mesh& m, Random& rnd, Vec3d centre, Vec3d radii, int leaves, double size) {
    for (int i = 0; i < leaves; ++i) {
        Vec3d p;
        do p = Vec3d(2 * rnd() - 1, 2 * rnd() - 1, 2 * rnd() - 1);
        while (dot(p, p) > 1);
        const Vec3d c = centre + p * radii;
        Vec3d u(2 * rnd() - 1, 2 * rnd() - 1, 2 * rnd() - 1), v(2 * rnd() - 1, 2 * rnd() - 1, 2 * rnd() - 1);
        if (length(cross(u, v)) < 1e-3) continue;
        u = normalize(u) * (0.5 * size);
        v = normalize(cross(cross(u, v), u)) * (0.5 * size);
        auto f = [](const Vec3d& q) { return Vec3(float(q.x), float(q.y), float(q.z)); };
        addQuad(m, f(c - u - v), f(c + u - v), f(c + u + v), f(c - u + v));
    }
}

}  // namespace

StylizerScene builtinForest() {
    StylizerScene s;
    Mesh groundMesh, treesMesh;
    addQuad(groundMesh, {-14, 0, -16}, {-14, 0, 14}, {14, 0, 14}, {14, 0, -16});
    Random rnd(2011);
    for (int gx = -2; gx <= 2; ++gx)
        for (int gz = -3; gz <= 1; ++gz) {
            const double x = 3.2 * gx + 1.4 * (rnd() - 0.5), z = 3.2 * gz + 1.4 * (rnd() - 0.5);
            const double h = 4.5 + 2.0 * rnd();
            addTrunk(treesMesh, x, z, 0, h, 0.22, 0.12, 7);
            addCanopy(treesMesh, rnd, {x, h + 0.6, z}, {1.9, 1.4, 1.9}, 260, 0.45);
        }
    s.occluders = {{"ground", std::make_shared<const Mesh>(std::move(groundMesh)), Mat4::identity(), {0.18, 0.16, 0.12}, {}},
                   {"trees", std::make_shared<const Mesh>(std::move(treesMesh)), Mat4::identity(), {0.16, 0.22, 0.10}, {}}};
    s.light.direction = {-0.45, 0.55, -0.7};  // a low sun behind the grove
    s.light.irradiance = {3.2, 2.9, 2.3};
    s.medium = {0.06, 0.9, {PhaseType::HenyeyGreenstein, 0.5}};
    s.camera.eye = {1.5, 1.7, 9.5};
    s.camera.target = {-0.5, 3.2, -2};
    s.camera.fovYDeg = 55;
    s.camera.width = 640;
    s.camera.height = 360;
    s.camera.farDist = 80;
    return s;
}

bool TransferFunction::operator==(const TransferFunction& o) const {
    return mode == o.mode && depthNear == o.depthNear && depthFar == o.depthFar && layers == o.layers && width == o.width &&
           height == o.height && (!layers.empty() || image == o.image);
}

}  // namespace volstyle::core

#include "core/solve/keyframe_solver.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "core/base/errors.h"
#include "core/solve/solver.h"
#include "core/volume/sequence.h"

namespace volstyle::core {
namespace {

/// The grid a key-frame solve works on.
std::vector<float>& propertyOf(Volume& v, Unknown u) { return u == Unknown::Emission ? v.ensureEmission() : v.ensureAlbedo(); }

void check(const std::vector<KeyFrame>& frames, const KeyFrameOptions& o) {
    if (frames.empty()) throw InvalidArgument("a key-frame solve needs at least one key frame");
    if (o.solve.unknown != Unknown::Emission && o.solve.unknown != Unknown::Albedo)
        throw InvalidArgument("key frames solve emission or albedo (each frame keeps its own extinction)");
    if (!(o.temporal >= 0 && o.temporal <= 1e9)) throw InvalidArgument("temporal must be in [0, 1e9]");
    if (o.sweeps < 1 || o.sweeps > 100) throw InvalidArgument("sweeps must be in [1, 100]");
    for (size_t k = 0; k < frames.size(); ++k) {
        const KeyFrame& f = frames[k];
        const std::string name = "key frame " + std::to_string(f.frame);
        f.volume.validate();
        if (!(f.volume.dims() == frames[0].volume.dims()) || !(f.volume.worldFromIndex() == frames[0].volume.worldFromIndex()))
            throw InvalidArgument(name + ": every key frame must share the first one's grid (dims and transform)");
        if (k > 0 && f.frame <= frames[k - 1].frame) throw InvalidArgument(name + ": frame numbers must increase");
        if (!f.velocity.empty() && f.velocity.size() != 3 * f.volume.voxelCount())
            throw InvalidArgument(name + ": its velocity grid has " + std::to_string(f.velocity.size() / 3) + " voxels, not " +
                                  std::to_string(f.volume.voxelCount()));
    }
}

/// Voxels a frame's property acts in: non-zero extinction.
std::vector<uint8_t> occupied(const Volume& v) {
    std::vector<uint8_t> known(v.voxelCount());
    for (size_t i = 0; i < known.size(); ++i)
        known[i] = (v.extinction()[3 * i] > 0 || v.extinction()[3 * i + 1] > 0 || v.extinction()[3 * i + 2] > 0) ? 1 : 0;
    return known;
}

}  // namespace

std::vector<Volume> solveKeyFrames(GpuDevice& device, const std::vector<KeyFrame>& frames, const Lighting& lighting, const KeyFrameOptions& o,
                                   KeyFrameReport* report, const std::function<void(int, int)>& progress) {
    check(frames, o);
    for (const KeyFrame& f : frames) requireDense(f.volume, "key-frame animation");
    const Unknown unknown = o.solve.unknown;
    const Int3 dims = frames[0].volume.dims();
    const Mat4 indexFromWorld = frames[0].volume.worldFromIndex().inverseAffine();
    std::vector<Volume> out;
    std::vector<std::vector<float>> velocity;  // index units per frame (empty: same voxel)
    for (const KeyFrame& f : frames) {
        out.push_back(f.volume);
        propertyOf(out.back(), unknown);  // present from the start
        velocity.push_back(o.followFlow && !f.velocity.empty() ? velocityInIndexUnits(f.velocity, indexFromWorld) : std::vector<float>{});
    }
    // Frame j's values carried to frame k (along j's velocity, or voxel for voxel).
    auto carried = [&](size_t j, size_t k) {
        return advect(propertyOf(out[j], unknown), dims, velocity[j], double(frames[k].frame - frames[j].frame));
    };
    KeyFrameReport rep;
    rep.frames.resize(frames.size());
    for (int sweep = 0; sweep < o.sweeps; ++sweep) {
        double change = 0;
        for (size_t k = 0; k < frames.size(); ++k) {
            if (progress) progress(sweep, int(k));
            // The neighbours' mean, carried here: the prior (sweep 0: none, each frame alone).
            std::vector<size_t> neighbours;
            if (k > 0) neighbours.push_back(k - 1);
            if (k + 1 < frames.size()) neighbours.push_back(k + 1);
            std::shared_ptr<std::vector<float>> prior;
            if (sweep > 0 && o.temporal > 0 && !neighbours.empty()) {
                prior = std::make_shared<std::vector<float>>(3 * out[k].voxelCount(), 0.0f);
                for (size_t j : neighbours) {
                    const std::vector<float> c = carried(j, k);
                    for (size_t i = 0; i < c.size(); ++i) (*prior)[i] += c[i] / float(neighbours.size());
                }
            }
            std::vector<float> before = propertyOf(out[k], unknown);
            if (frames[k].views.empty()) {
                if (!prior) continue;  // nothing to go on yet
                propertyOf(out[k], unknown) = *prior;  // its own least-squares answer: the prior itself
            } else {
                SolveOptions so = o.solve;
                so.localResolve = false;
                if (prior) so.prior = {prior, o.temporal * double(neighbours.size())};
                Solver solver(device, out[k], lighting, frames[k].views, so);
                SolveResult r = solver.run();
                rep.frames[k] = r.report;
                propertyOf(out[k], unknown) = std::move(propertyOf(r.volume, unknown));
            }
            if (o.extendIntoEmpty) extendByDiffusion(propertyOf(out[k], unknown), dims, occupied(out[k]));
            const std::vector<float>& now = propertyOf(out[k], unknown);
            for (size_t i = 0; i < now.size(); ++i) change = std::max(change, double(std::abs(now[i] - before[i])));
        }
        rep.change.push_back(change);
        rep.sweeps = sweep + 1;
    }
    if (report) *report = std::move(rep);
    return out;
}

std::vector<float> frameFromKeys(const std::vector<KeyFrame>& keys, const std::vector<Volume>& solved, Unknown unknown, int f,
                                 bool followFlow) {
    if (keys.empty() || keys.size() != solved.size()) throw InvalidArgument("frameFromKeys: one solved volume per key frame");
    auto property = [&](size_t k) -> const std::vector<float>& {
        const Volume& v = solved[k];
        return unknown == Unknown::Emission ? v.emission() : v.albedo();
    };
    auto velocity = [&](size_t k) { return followFlow ? keys[k].velocity : std::vector<float>{}; };
    const Volume& grid = solved[0];
    size_t next = 0;
    while (next < keys.size() && keys[next].frame < f) ++next;
    if (next < keys.size() && keys[next].frame == f) return property(next);
    if (next == 0 || next == keys.size()) {
        const size_t k = next == 0 ? 0 : keys.size() - 1;
        const auto index = velocity(k).empty() ? std::vector<float>{} : velocityInIndexUnits(velocity(k), grid.worldFromIndex().inverseAffine());
        return advect(property(k), grid.dims(), index, double(f - keys[k].frame));
    }
    return inBetween(property(next - 1), keys[next - 1].frame, velocity(next - 1), property(next), keys[next].frame, velocity(next), f,
                     grid.dims(), grid.worldFromIndex());
}

std::vector<float> inBetween(const std::vector<float>& a, int fa, const std::vector<float>& velocityA, const std::vector<float>& b, int fb,
                             const std::vector<float>& velocityB, int f, Int3 dims, const Mat4& worldFromIndex) {
    if (!(fa < fb) || f < fa || f > fb) throw InvalidArgument("inBetween: the frame must lie between its key frames");
    const Mat4 indexFromWorld = worldFromIndex.inverseAffine();
    auto index = [&](const std::vector<float>& v) { return v.empty() ? v : velocityInIndexUnits(v, indexFromWorld); };
    const std::vector<float> fromA = advect(a, dims, index(velocityA), double(f - fa));
    const std::vector<float> fromB = advect(b, dims, index(velocityB), double(f - fb));
    return blend(fromA, fromB, double(f - fa) / double(fb - fa));
}

}  // namespace volstyle::core

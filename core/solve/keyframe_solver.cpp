#include "core/solve/keyframe_solver.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
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
        const BrickLayout *bricks = f.volume.bricks(), *first = frames[0].volume.bricks();
        if (bool(bricks) != bool(first) || (bricks && !(*bricks == *first)) || (bricks && bricks->hasSharedSlots()))
            throw InvalidArgument(name + " is not stored on the same bricks as key frame " + std::to_string(frames[0].frame) +
                                  ", or shares tile slots: put the sequence's frames on one brick layout first (putFramesOnOneLayout)");
        if (!f.velocity.empty() && f.velocity.size() != 3 * f.volume.storedVoxels())
            throw InvalidArgument(name + ": its velocity grid has " + std::to_string(f.velocity.size() / 3) + " voxels, not " +
                                  std::to_string(f.volume.storedVoxels()));
    }
}

/// Voxels a frame's property acts in: non-zero extinction (per stored voxel).
std::vector<uint8_t> occupied(const Volume& v) {
    std::vector<uint8_t> known(v.storedVoxels());
    for (size_t i = 0; i < known.size(); ++i)
        known[i] = (v.extinction()[3 * i] > 0 || v.extinction()[3 * i + 1] > 0 || v.extinction()[3 * i + 2] > 0) ? 1 : 0;
    return known;
}

/// The solved property of `solved` on `frame`'s layout: the same grid, or (a sparse solve that
/// activated more bricks than the frame has) its values in the frame's bricks.
std::vector<float> onLayoutOf(const Volume& frame, Volume& solved, Unknown u) {
    if (!frame.isSparse() || *frame.bricks() == *solved.bricks()) return std::move(propertyOf(solved, u));
    return gridOnBricks(solved, propertyOf(solved, u), 3, *frame.bricks(), 0.0f);
}

}  // namespace

void putFramesOnOneLayout(const std::vector<Volume*>& frames, const std::vector<std::vector<float>*>& velocities, Unknown unknown) {
    const auto sparse = std::find_if(frames.begin(), frames.end(), [](const Volume* v) { return v->isSparse(); });
    if (sparse == frames.end()) return;
    const BrickLayout& reference = *(*sparse)->bricks();
    BrickLayout shared(reference.dims(), reference.offset());
    for (size_t i = 0; i < frames.size(); ++i) {
        const Volume* frame = frames[i];
        std::optional<Volume> converted;  // a dense frame's bricks: those that hold data
        const Volume& asBricks = frame->isSparse() ? *frame : converted.emplace(frame->toSparse(reference.offset()));
        if (!(asBricks.dims() == reference.dims()) || !(asBricks.bricks()->offset() == reference.offset()))
            throw InvalidArgument("the sequence's frame #" + std::to_string(i + 1) + " is not on the first sparse frame's grid " +
                                  "(its dims, or where its bricks start, differ): a sequence's frames must share one grid to be solved together");
        asBricks.bricks()->forEachActiveBrick([&](Int3 b, uint32_t) { shared.activate(b); });
        for (const Int3& b : sparseSolveApron(asBricks, unknown)) shared.activate(b);
    }
    for (size_t i = 0; i < frames.size(); ++i) {
        if (frames[i]->isSparse() && *frames[i]->bricks() == shared) continue;
        if (i < velocities.size() && velocities[i] && !velocities[i]->empty())
            *velocities[i] = gridOnBricks(*frames[i], *velocities[i], 3, shared, 0.0f);
        *frames[i] = frames[i]->onBricks(shared);
    }
}

std::vector<Volume> solveKeyFrames(GpuDevice& device, const std::vector<KeyFrame>& frames, const Lighting& lighting, const KeyFrameOptions& o,
                                   KeyFrameReport* report, const std::function<void(int, int)>& progress) {
    check(frames, o);
    const Unknown unknown = o.solve.unknown;
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
        return advect(propertyOf(out[j], unknown), GridSpace::of(out[j]), velocity[j], double(frames[k].frame - frames[j].frame));
    };
    KeyFrameReport rep;
    rep.frames.resize(frames.size());
    rep.startRms.resize(frames.size());
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
                prior = std::make_shared<std::vector<float>>(3 * out[k].storedVoxels(), 0.0f);
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
                const auto t0 = Clock::now();
                Solver solver(device, out[k], lighting, frames[k].views, so);
                SolveResult r = solver.run();
                rep.solveSeconds += msSince(t0) / 1000;
                if (rep.startRms[k].empty()) rep.startRms[k] = r.report.initialRms;
                rep.frames[k] = r.report;
                propertyOf(out[k], unknown) = onLayoutOf(out[k], r.volume, unknown);
            }
            const auto t0 = Clock::now();
            if (o.extendIntoEmpty) extendByDiffusion(propertyOf(out[k], unknown), GridSpace::of(out[k]), occupied(out[k]));
            rep.extendSeconds += msSince(t0) / 1000;
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
        return advect(property(k), GridSpace::of(grid), index, double(f - keys[k].frame));
    }
    return inBetween(property(next - 1), keys[next - 1].frame, velocity(next - 1), property(next), keys[next].frame, velocity(next), f,
                     GridSpace::of(grid), grid.worldFromIndex());
}

std::vector<float> inBetween(const std::vector<float>& a, int fa, const std::vector<float>& velocityA, const std::vector<float>& b, int fb,
                             const std::vector<float>& velocityB, int f, const GridSpace& space, const Mat4& worldFromIndex) {
    if (!(fa < fb) || f < fa || f > fb) throw InvalidArgument("inBetween: the frame must lie between its key frames");
    const Mat4 indexFromWorld = worldFromIndex.inverseAffine();
    auto index = [&](const std::vector<float>& v) { return v.empty() ? v : velocityInIndexUnits(v, indexFromWorld); };
    const std::vector<float> fromA = advect(a, space, index(velocityA), double(f - fa));
    const std::vector<float> fromB = advect(b, space, index(velocityB), double(f - fb));
    return blend(fromA, fromB, double(f - fa) / double(fb - fa));
}

}  // namespace volstyle::core

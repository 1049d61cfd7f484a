// Animated volumes (issue #16): key frames solved jointly with a temporal term, voxel for voxel or
// along the sequence's velocity. A ball of smoke moves +0.3 along x per frame and carries a
// pattern (its right half bright): views on frames 0 and 2 give frame 1 in between; with views
// on frame 0 only, the flow carries the pattern to where frame 1's ball is.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/render/gpu_volume.h"
#include "core/solve/keyframe_solver.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/sequence.h"
#include "../common/image_compare.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

constexpr double kSpeed = 0.3;  // world units per frame, along +x
constexpr int kRes = 16;

/// Frame f: a ball of `radius` (world units; the box is [-1, 1]³ in `res`³ voxels) centred at
/// x = −0.3 + 0.3 f; with `emission`, its right half (relative to the ball) emits 1, the rest 0.2
/// (the pattern the ball carries).
Volume frameVolume(int f, bool emission, int res = kRes, double radius = 0.45) {
    const Int3 dims{res, res, res};
    Volume v(dims, unitBoxWorldFromIndex(dims));
    auto& e = v.ensureEmission();
    const Vec3d centre(-0.3 + kSpeed * f, 0, 0);
    for (int k = 0; k < res; ++k)
        for (int j = 0; j < res; ++j)
            for (int i = 0; i < res; ++i) {
                const Vec3d x = v.worldFromIndex().applyPoint({double(i), double(j), double(k)});
                const double r = length(x - centre);
                const size_t n = 3 * v.index(i, j, k);
                const float sigma = r < radius ? 3.0f : 0.0f;
                v.extinction()[n] = v.extinction()[n + 1] = v.extinction()[n + 2] = sigma;
                const float value = emission && sigma > 0 ? (x.x > centre.x ? 1.0f : 0.2f) : 0.0f;
                e[n] = e[n + 1] = e[n + 2] = value;
            }
    return v;
}

std::vector<float> velocity(int res = kRes) {
    std::vector<float> v(3 * size_t(res) * res * res, 0.0f);
    for (size_t i = 0; i < v.size(); i += 3) v[i] = float(kSpeed);
    return v;
}

std::vector<Camera> views(int count, int size) {
    std::vector<Camera> cams;
    for (int i = 0; i < count; ++i) {
        const double a = 0.4 + 2 * std::numbers::pi * i / count;
        Camera c;
        c.eye = {2.8 * std::sin(a), 0.6, 2.8 * std::cos(a)};
        c.target = {0.01, 0.0, 0.02};
        c.width = c.height = size;
        cams.push_back(c);
    }
    return cams;
}

Lighting dark() {
    Lighting l;
    l.lights.clear();
    l.background.color = {0, 0, 0};
    return l;
}

KeyFrame keyFrame(int f, bool withViews, int res = kRes, double radius = 0.45) {
    KeyFrame k;
    k.frame = f;
    k.volume = frameVolume(f, false, res, radius);
    k.velocity = velocity(res);
    if (withViews) {
        GpuVolume truth(frameVolume(f, true, res, radius));
        for (const Camera& c : views(3, 24))
            k.views.push_back({"f" + std::to_string(f) + "v" + std::to_string(k.views.size()), c, test::sharedRenderer().render(truth, c, dark()), std::nullopt});
    }
    return k;
}

double rms(const Image& a, const Image& b) { return test::rmsDifference(a, b); }

/// RMS over three views between frame 1 (`v`, its emission set) and the truth.
double frameOneError(const Volume& v, int res = kRes, double radius = 0.45) {
    GpuVolume gpu(v), truth(frameVolume(1, true, res, radius));
    double sum = 0;
    for (const Camera& c : views(3, 24)) sum += rms(test::sharedRenderer().render(gpu, c, dark()), test::sharedRenderer().render(truth, c, dark()));
    return sum / 3;
}

double frameOneError(const std::vector<float>& emission) {
    Volume v = frameVolume(1, false);
    v.emission() = emission;
    return frameOneError(v);
}

/// The x of the emission's bright part (values over 0.6) in frame f's ball.
double brightCentre(const Volume& v, int f) {
    const Volume shape = frameVolume(f, false);
    double sx = 0, n = 0;
    for (int k = 0; k < kRes; ++k)
        for (int j = 0; j < kRes; ++j)
            for (int i = 0; i < kRes; ++i) {
                const size_t e = 3 * v.index(i, j, k);
                if (shape.extinction()[e] <= 0 || v.emission()[e] < 0.6f) continue;
                sx += v.worldFromIndex().applyPoint({double(i), double(j), double(k)}).x, n += 1;
            }
    return n > 0 ? sx / n : 1e9;
}

}  // namespace

TEST(Animation, KeyFramesZeroAndTwoGiveFrameOneInBetween) {
    VOLSTYLE_REQUIRE_GL();
    const std::vector<KeyFrame> frames{keyFrame(0, true), keyFrame(2, true)};
    KeyFrameOptions o;
    o.solve.maxIterations = 40;
    o.solve.tolerance = 1e-6;
    o.temporal = 0.05;
    o.sweeps = 3;
    KeyFrameReport report;
    const auto solved = solveKeyFrames(test::device(), frames, dark(), o, &report);
    ASSERT_EQ(solved.size(), 2u);
    ASSERT_EQ(report.sweeps, 3);
    const std::vector<float> zero(3 * size_t(kRes) * kRes * kRes, 0.0f);
    const Mat4 m = frames[0].volume.worldFromIndex();
    const double start = frameOneError(zero);
    const double withFlow = frameOneError(inBetween(solved[0].emission(), 0, velocity(), solved[1].emission(), 2, velocity(), 1, Int3{kRes, kRes, kRes}, m));
    const double sameVoxel = frameOneError(inBetween(solved[0].emission(), 0, {}, solved[1].emission(), 2, {}, 1, Int3{kRes, kRes, kRes}, m));
    std::cout << "[ measured ] frame 1 between key frames 0 and 2: RMS " << start << " (no emission) -> " << withFlow << " along the flow, "
              << sameVoxel << " voxel for voxel; sweeps changed " << report.change[0] << ", " << report.change[1] << ", " << report.change[2] << "\n";
    EXPECT_LE(withFlow, 0.15 * start);
    EXPECT_LT(withFlow, sameVoxel);
    EXPECT_LE(report.change.back(), report.change[1] + 1e-6) << "the sweeps settle";
}

TEST(Animation, TheFlowCarriesAPatternToWhereTheNextFrameIs) {
    VOLSTYLE_REQUIRE_GL();
    // Views on frame 0 only: frame 1 learns its emission from frame 0 through the temporal term.
    const std::vector<KeyFrame> frames{keyFrame(0, true), keyFrame(1, false)};
    KeyFrameOptions o;
    o.solve.maxIterations = 30;
    o.temporal = 0.05;
    o.sweeps = 2;
    const auto flow = solveKeyFrames(test::device(), frames, dark(), o);
    o.followFlow = false;
    const auto same = solveKeyFrames(test::device(), frames, dark(), o);
    const double x0 = brightCentre(flow[0], 0), x1 = brightCentre(flow[1], 1), x1same = brightCentre(same[1], 1);
    std::cout << "[ measured ] the bright half's centre: frame 0 x = " << x0 << "; frame 1 along the flow x = " << x1 << " (moved "
              << x1 - x0 << ", the velocity " << kSpeed << "), voxel for voxel x = " << x1same << "\n";
    EXPECT_NEAR(x1 - x0, kSpeed, 0.08);
    EXPECT_LT(std::abs(x1 - x0 - kSpeed), std::abs(x1same - x0 - kSpeed)) << "without the flow the pattern stays behind";
}

TEST(Animation, DiffusionFillsEmptyVoxelsFromTheirNeighbours) {
    // A 1D ramp known at both ends: the harmonic extension is linear in between.
    const Int3 n{9, 1, 1};
    std::vector<float> g(27, 0.0f);
    std::vector<uint8_t> known(9, 0);
    known[0] = known[8] = 1;
    for (int c = 0; c < 3; ++c) g[size_t(c)] = 0.0f, g[24 + size_t(c)] = 8.0f;
    extendByDiffusion(g, n, known, 5000, 1e-7);
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(g[3 * size_t(i)], float(i), 1e-3) << i;
    // Advection by a whole voxel per frame moves values exactly.
    std::vector<float> v(27, 0.0f);
    for (size_t i = 0; i < v.size(); i += 3) v[i] = 1.0f;
    const auto moved = advect(g, n, v, 2.0);
    for (int i = 2; i < 9; ++i) EXPECT_NEAR(moved[3 * size_t(i)], g[3 * size_t(i - 2)], 1e-5);
}

TEST(Animation, SparseKeyFramesFollowTheDenseSolve) {
    VOLSTYLE_REQUIRE_GL();
    // A small ball in a 48³ box: the frames' shared bricks are a fraction of the box. The same key
    // frames are solved dense and sparse (issue #39); frame 1 is filled from them.
    constexpr int kBig = 48;
    constexpr double kRadius = 0.25;
    const std::vector<KeyFrame> dense{keyFrame(0, true, kBig, kRadius), keyFrame(2, true, kBig, kRadius)};
    std::vector<KeyFrame> sparse = dense;
    Volume between = frameVolume(1, false, kBig, kRadius).toSparse();
    // The key frames go in dense: stored sparse on the layout `between` shares, velocities along.
    putFramesOnOneLayout({&sparse[0].volume, &sparse[1].volume, &between}, {&sparse[0].velocity, &sparse[1].velocity, nullptr},
                         Unknown::Emission);
    ASSERT_TRUE(sparse[0].volume.isSparse() && sparse[1].volume.isSparse());
    const double stored = double(between.storedVoxels()) / double(between.voxelCount());
    // Each frame alone (one sweep): the sparse solve is the dense one, in the medium.
    KeyFrameOptions o;
    o.solve.maxIterations = 10;
    o.sweeps = 1;
    double worst = 0;
    {
        const auto solvedDense = solveKeyFrames(test::device(), dense, dark(), o), solvedSparse = solveKeyFrames(test::device(), sparse, dark(), o);
        for (size_t k = 0; k < 2; ++k)
            forEachActiveVoxel(dense[k].volume, [&](Int3 p, size_t n) {
                if (dense[k].volume.extinction()[3 * n] <= 0) return;
                const size_t s = solvedSparse[k].index(p.x, p.y, p.z);
                for (int c = 0; c < 3; ++c)
                    worst = std::max(worst, double(std::abs(solvedSparse[k].emission()[3 * s + size_t(c)] - solvedDense[k].emission()[3 * n + size_t(c)])));
            });
    }
    // Coupled (two sweeps): frame 1 between them, against the truth. The priors differ a little:
    // a dense frame's values are extended into the whole box, a sparse one's into its bricks.
    o.solve.maxIterations = 30;
    o.temporal = 0.05;
    o.sweeps = 2;
    const auto solvedDense = solveKeyFrames(test::device(), dense, dark(), o), solvedSparse = solveKeyFrames(test::device(), sparse, dark(), o);
    Volume denseOne = frameVolume(1, false, kBig, kRadius), none = denseOne;
    none.ensureEmission();
    denseOne.emission() = frameFromKeys(dense, solvedDense, Unknown::Emission, 1, true);
    between.emission() = frameFromKeys(sparse, solvedSparse, Unknown::Emission, 1, true);
    const double start = frameOneError(none, kBig, kRadius), errDense = frameOneError(denseOne, kBig, kRadius),
                 errSparse = frameOneError(between, kBig, kRadius);
    std::cout << "[ measured ] sparse key frames store " << 100 * stored << "% of the box; alone, their emission differs from the dense "
              << "solve's by at most " << worst << " in the medium; coupled, frame 1: RMS " << start << " (no emission) -> " << errDense
              << " dense, " << errSparse << " sparse\n";
    EXPECT_LE(stored, 0.2);
    EXPECT_LE(worst, 1e-5);
    EXPECT_LE(errSparse, 0.1 * start);
    EXPECT_NEAR(errSparse, errDense, 0.05 * errDense);
}

TEST(Animation, SparseKeyFramesSolveOnCoarsenedUnknownsToo) {
    VOLSTYLE_REQUIRE_GL();
    // A sparse solve whose vectors would not fit the GPU's storage blocks coarsens its unknowns;
    // the temporal prior, given per stored voxel, then follows them. CTest's
    // gl_sparse_key_frames_small_blocks runs this with VOLSTYLE_MAX_STORAGE_BLOCK_BYTES=65536
    // (4,096 unknowns), where these frames solve at half resolution.
    constexpr int kBig = 48;
    constexpr double kRadius = 0.25;
    std::vector<KeyFrame> keys{keyFrame(0, true, kBig, kRadius), keyFrame(2, true, kBig, kRadius)};
    Volume between = frameVolume(1, false, kBig, kRadius).toSparse();
    putFramesOnOneLayout({&keys[0].volume, &keys[1].volume, &between}, {&keys[0].velocity, &keys[1].velocity, nullptr}, Unknown::Emission);
    KeyFrameOptions o;
    o.solve.maxIterations = 20;
    o.temporal = 0.05;
    o.sweeps = 2;
    KeyFrameReport report;
    const auto solved = solveKeyFrames(test::device(), keys, dark(), o, &report);
    Volume none = frameVolume(1, false, kBig, kRadius);
    none.ensureEmission();
    between.emission() = frameFromKeys(keys, solved, Unknown::Emission, 1, true);
    const double start = frameOneError(none, kBig, kRadius), err = frameOneError(between, kBig, kRadius);
    const bool coarse = report.frames[0].unknownCount < keys[0].volume.storedVoxels();
    std::cout << "[ measured ] storage blocks of " << test::device().capabilities().maxStorageBlockBytes << " bytes: "
              << report.frames[0].unknownCount << " unknowns for " << keys[0].volume.storedVoxels() << " stored voxels; frame 1: RMS "
              << start << " (no emission) -> " << err << "\n";
    EXPECT_LE(err, 0.25 * start);
    if (std::getenv("VOLSTYLE_MAX_STORAGE_BLOCK_BYTES")) {
        EXPECT_TRUE(coarse) << "the small blocks coarsened the unknowns";
    }
}

TEST(Animation, SparseCarryAndDiffusionAreTheDenseOnesOnFullBricks) {
    // Every brick active: the same voxels, the same arithmetic, bit for bit (a box that is not a
    // whole number of bricks, so edge bricks stick out of it).
    const Int3 n{12, 10, 9};
    Volume dense(n, Mat4::identity());
    std::vector<float> velocity(3 * dense.voxelCount());
    std::vector<uint8_t> known(dense.voxelCount());
    auto& g = dense.ensureEmission();
    for (size_t i = 0; i < g.size(); ++i) g[i] = float((i * 7919) % 101) / 100.0f, velocity[i] = float((i * 104729) % 61) / 20.0f - 1.5f;
    for (size_t i = 0; i < known.size(); ++i) known[i] = (i * 31) % 7 < 2;
    const Volume sparse = dense.onBricks(BrickLayout::full(n, {3, 0, 5}));
    const GridSpace space = GridSpace::of(sparse);
    const std::vector<float> sparseVelocity = gridOnBricks(dense, velocity, 3, *sparse.bricks(), 0.0f);
    std::vector<uint8_t> sparseKnown(sparse.storedVoxels(), 0);
    forEachActiveVoxel(sparse, [&](Int3 p, size_t s) { sparseKnown[s] = known[dense.index(p.x, p.y, p.z)]; });
    const std::vector<float> carried = advect(g, n, velocity, 1.7), sparseCarried = advect(sparse.emission(), space, sparseVelocity, 1.7);
    std::vector<float> extended = g, sparseExtended = sparse.emission();
    extendByDiffusion(extended, n, known, 50, 0);
    extendByDiffusion(sparseExtended, space, sparseKnown, 50, 0);
    size_t differ = 0;
    forEachActiveVoxel(dense, [&](Int3 p, size_t d) {
        const size_t s = sparse.index(p.x, p.y, p.z);
        for (int c = 0; c < 3; ++c)
            differ += carried[3 * d + size_t(c)] != sparseCarried[3 * s + size_t(c)] || extended[3 * d + size_t(c)] != sparseExtended[3 * s + size_t(c)];
    });
    EXPECT_EQ(differ, 0u);
}

TEST(Animation, SparseDiffusionStopsAtInactiveBricks) {
    // Bricks 0 and 1 of a 24-voxel row active, brick 2 not: known 0 at voxel 0 and 8 at voxel 8,
    // the rest of the active region is zero-flux at brick 2 (8 throughout), which keeps the background.
    BrickLayout bricks(Int3{24, 1, 1}, {0, 0, 0});
    bricks.activate({0, 0, 0}), bricks.activate({1, 0, 0});
    Volume v(bricks, Mat4::identity());
    auto& g = v.ensureEmission();
    std::vector<uint8_t> known(v.storedVoxels(), 0);
    for (int i : {0, 8}) {
        const size_t s = v.index(i, 0, 0);
        known[s] = 1;
        g[3 * s] = g[3 * s + 1] = g[3 * s + 2] = float(i);
    }
    extendByDiffusion(g, GridSpace::of(v), known, 20000, 1e-7);
    for (int i = 0; i < 16; ++i) EXPECT_NEAR(g[3 * v.index(i, 0, 0)], float(std::min(i, 8)), 1e-3) << i;
    for (int i = 16; i < 24; ++i) EXPECT_EQ(g[3 * v.index(i, 0, 0)], 0.0f) << i << ": the background";
}

TEST(Animation, TheParallelDiffusionIsTheSerialOne) {
    // 70 K free voxels, so the Jacobi sweeps split among the cores (a core per 32 K): each sweep reads only the
    // last one's values, so the result is a serial Jacobi's bit for bit (written out here).
    const Int3 n{80, 64, 16};
    const size_t count = size_t(n.volume());
    std::vector<float> g(3 * count);
    std::vector<uint8_t> known(count);
    for (size_t i = 0; i < count; ++i) known[i] = i % 7 == 0, g[3 * i] = g[3 * i + 1] = g[3 * i + 2] = known[i] ? float(i % 101) / 10 : 0.0f;
    std::vector<float> serial = g;
    Vec3d mean(0, 0, 0);
    double m = 0;
    for (size_t i = 0; i < count; ++i)
        if (known[i]) mean += Vec3d(g[3 * i], g[3 * i + 1], g[3 * i + 2]), m += 1;
    mean = mean * (1 / m);
    for (size_t i = 0; i < count; ++i)
        if (!known[i]) serial[3 * i] = float(mean.x), serial[3 * i + 1] = float(mean.y), serial[3 * i + 2] = float(mean.z);
    for (int sweep = 0; sweep < 20; ++sweep) {
        std::vector<float> next = serial;
        for (int k = 0; k < n.z; ++k)
            for (int j = 0; j < n.y; ++j)
                for (int i = 0; i < n.x; ++i) {
                    const size_t v = (size_t(k) * size_t(n.y) + size_t(j)) * size_t(n.x) + size_t(i);
                    if (known[v]) continue;
                    Vec3d sum(0, 0, 0);
                    int neighbours = 0;
                    const int offsets[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
                    for (const auto& o : offsets) {
                        const int a = i + o[0], b = j + o[1], c = k + o[2];
                        if (a < 0 || b < 0 || c < 0 || a >= n.x || b >= n.y || c >= n.z) continue;
                        const size_t e = 3 * ((size_t(c) * size_t(n.y) + size_t(b)) * size_t(n.x) + size_t(a));
                        sum += Vec3d(serial[e], serial[e + 1], serial[e + 2]), ++neighbours;
                    }
                    const Vec3d value = sum * (1.0 / std::max(neighbours, 1));
                    for (int ch = 0; ch < 3; ++ch) next[3 * v + size_t(ch)] = float(value[ch]);
                }
        serial = next;
    }
    extendByDiffusion(g, n, known, 20, 0);
    size_t differ = 0;
    for (size_t i = 0; i < g.size(); ++i) differ += g[i] != serial[i];
    EXPECT_EQ(differ, 0u);
}

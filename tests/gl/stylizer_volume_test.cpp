// The stylizer on a heterogeneous medium (issue #15, beyond the paper): a homogeneous VDB filling a
// box around everything gives the homogeneous path's frame and V̄ back, and V̄ under a dense slab
// (the σt-weighted average of the light's transmittance along the view ray) matches a CPU
// reference integrated at 100× the resolution.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "../common/image_compare.h"
#include "../common/small_forest.h"
#include "core/render/gpu_volume.h"
#include "core/stylize/medium_gpu.h"
#include "core/stylize/stylizer.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A volume of `n`³ voxels with grey σt from `sigma(i, j, k)` (the scene's box places it).
Volume grid(int n, double (*sigma)(int, int, int, int)) {
    Volume g({n, n, n}, unitBoxWorldFromIndex({n, n, n}));
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const float s = float(sigma(i, j, k, n));
                g.setExtinction(i, j, k, {s, s, s});
            }
    return g;
}

/// σt of `g` at `x` as the GPU samples it: trilinear between voxel centres over [lo, hi], clamped.
double sampleGrid(const Volume& g, Vec3d lo, Vec3d hi, Vec3d x) {
    double f[3];
    int i0[3], i1[3];
    for (int a = 0; a < 3; ++a) {
        const int n = g.dims()[a];
        const double c = std::clamp((x[a] - lo[a]) / (hi[a] - lo[a]) * n - 0.5, 0.0, double(n - 1));
        i0[a] = int(c), i1[a] = std::min(i0[a] + 1, n - 1), f[a] = c - i0[a];
    }
    auto at = [&](int i, int j, int k) { return double(g.extinction()[3 * ((size_t(k) * g.dims().y + size_t(j)) * g.dims().x + size_t(i))]); };
    double v = 0;
    for (int c = 0; c < 8; ++c) {
        const double w = (c & 1 ? f[0] : 1 - f[0]) * (c & 2 ? f[1] : 1 - f[1]) * (c & 4 ? f[2] : 1 - f[2]);
        v += w * at(c & 1 ? i1[0] : i0[0], c & 2 ? i1[1] : i0[1], c & 4 ? i1[2] : i0[2]);
    }
    return v;
}

/// σt of a round blob off the centre of an n³ grid, 0 outside it.
double blob(int i, int j, int k, int n) {
    const double x = (i + 0.5) / n - 0.45, y = (j + 0.5) / n - 0.5, z = (k + 0.5) / n - 0.55;
    return std::max(0.0, 1 - 30 * (x * x + y * y + z * z));
}

/// The small forest with a volume medium in a box among the trees (σt × 1.5).
StylizerScene forestWithBlobBox() {
    StylizerScene scene = test::smallForest();
    StylizerVolume v;
    v.lo = {-7, 0, -8}, v.hi = {5, 7, 2};
    v.extinctionScale = 1.5;
    scene.volume = v;
    return scene;
}

}  // namespace

TEST(StylizerVolume, AHomogeneousVdbFillingTheSceneIsTheHomogeneousMedium) {
    VOLSTYLE_REQUIRE_GL();
    StylizerScene homogeneous = test::smallForest();
    StylizeSettings naive;
    naive.method = VisibilityMethod::Naive;
    naive.steps = 128;
    StylizerScene volume = homogeneous;
    StylizerVolume v;
    Volume fromFile;
    {  // a homogeneous VDB, written and read back as a user's file would be (σt 1, scaled below)
        Volume constant({4, 4, 4}, unitBoxWorldFromIndex({4, 4, 4}));
        for (int k = 0; k < 4; ++k)
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) constant.setExtinction(i, j, k, {1, 1, 1});
        const std::string path = (std::filesystem::temp_directory_path() / "volstyle-stylizer-homogeneous.vdb").string();
        saveVdb(path, constant);
        fromFile = loadVdb(path);
        std::filesystem::remove(path);
    }
    v.extinctionScale = homogeneous.medium.extinction;
    v.lo = {-300, -300, -300}, v.hi = {300, 300, 300};  // every ray's [0, s] inside (s ≤ far = 80)
    v.steps = naive.steps;                             // the same midpoints as the naive V̄
    v.lightTransmittance = false;                      // the homogeneous model does not dim the sun
    volume.volume = v;
    Stylizer stylizer(test::device());
    GpuVolume medium(fromFile);
    const StylizedFrame a = stylizer.render(homogeneous, naive), b = stylizer.render(volume, naive, &medium);
    const double frame = test::maxAbsDifference(a.frame, b.frame), vBar = test::maxAbsDifference(a.averageVisibility, b.averageVisibility);
    std::printf("[ measured ] homogeneous VDB vs the homogeneous path: frame %.2e, V̄ %.2e, scattering %.2e (max abs)\n", frame, vBar,
                test::maxAbsDifference(a.scattering, b.scattering));
    EXPECT_LE(frame, 1e-3);
    EXPECT_LE(vBar, 1e-3);
    // The accelerated V̄ on the homogeneous side: the volume's 128 midpoints are within a few 1e-2.
    const StylizedFrame exact = stylizer.render(homogeneous);
    std::printf("[ measured ] the volume's 128-step V̄ vs the exact (accelerated) one: %.2e\n",
                test::maxAbsDifference(exact.averageVisibility, b.averageVisibility));
}

TEST(StylizerVolume, AverageVisibilityUnderADenseSlabMatchesACpuReference) {
    VOLSTYLE_REQUIRE_GL();
    // A box [-4, 4]³ of thin haze with a dense slab at 1 < y < 2.5; the sun straight above; the
    // only occluder a small quad below the box (nothing shadows the medium but the slab).
    StylizerScene scene;
    Mesh quad;
    const Vec3 a{-1, -6, -1}, b{1, -6, -1}, c{1, -6, 1}, d{-1, -6, 1};
    for (const Vec3& p : {a, b, c, d}) quad.positions.push_back(p), quad.normals.push_back({0, 1, 0});
    quad.indices = {0, 1, 2, 0, 2, 3};
    scene.occluders = {{"quad", std::make_shared<const Mesh>(quad), Mat4::identity(), {0.5, 0.5, 0.5}, {}}};
    scene.light.direction = {0, 1, 0};
    scene.light.shadowMapSize = 512;
    scene.medium = {0.0, 0.9, {PhaseType::Isotropic, 0}};
    scene.camera.eye = {0, 0.5, -12};
    scene.camera.target = {0, 0.5, 0};
    scene.camera.fovYDeg = 40;
    scene.camera.width = 32, scene.camera.height = 32;
    scene.camera.farDist = 30;
    StylizerVolume v;
    const Volume slab = grid(32, [](int, int j, int, int n) { return (j + 0.5) / n * 8 - 4 > 1 && (j + 0.5) / n * 8 - 4 < 2.5 ? 1.5 : 0.05; });
    v.lo = {-4, -4, -4}, v.hi = {4, 4, 4};
    v.steps = 256;
    scene.volume = v;
    Stylizer stylizer(test::device());
    GpuVolume medium(slab);
    const StylizedFrame f = stylizer.render(scene, {}, &medium);
    // σt depends on y alone (so does T_l, the sun straight above): τ_l(y) = ∫_y^4 σt, tabulated.
    constexpr int kTable = 100000;
    std::vector<double> tauAbove(kTable + 1, 0.0);  // at y = -4 + 8 i / kTable
    for (int i = kTable - 1; i >= 0; --i)
        tauAbove[size_t(i)] = tauAbove[size_t(i) + 1] + sampleGrid(slab, v.lo, v.hi, {0, -4 + 8 * (i + 0.5) / kTable, 0}) * 8.0 / kTable;
    auto lightDepth = [&](double y) {
        const double c = std::clamp((y + 4) / 8 * kTable, 0.0, double(kTable));
        const int i = std::min(int(c), kTable - 1);
        return tauAbove[size_t(i)] + (c - i) * (tauAbove[size_t(i) + 1] - tauAbove[size_t(i)]);
    };
    double worst = 0;
    int compared = 0, worstX = 0, worstY = 0;
    for (int y = 2; y < 32; y += 5)
        for (int x = 2; x < 32; x += 5) {
            // The reference: 20,000 midpoints along the ray's part in the box.
            const Vec3d dir = scene.camera.rayDirection(x, y), e = scene.camera.eye;
            double ta = 0, tb = 30;
            for (int k = 0; k < 3; ++k) {
                if (std::abs(dir[k]) < 1e-12) continue;
                const double t0 = (v.lo[k] - e[k]) / dir[k], t1 = (v.hi[k] - e[k]) / dir[k];
                ta = std::max(ta, std::min(t0, t1)), tb = std::min(tb, std::max(t0, t1));
            }
            if (!(tb > ta)) continue;
            double num = 0, den = 0;
            for (int i = 0; i < 20000; ++i) {
                const Vec3d p = e + dir * (ta + (i + 0.5) / 20000 * (tb - ta));
                const double sigma = sampleGrid(slab, v.lo, v.hi, p);
                num += sigma * std::exp(-lightDepth(p.y)), den += sigma;
            }
            const double want = num / den, got = f.averageVisibility.pixel(x, y)[0];
            if (std::abs(got - want) > worst) worst = std::abs(got - want), worstX = x, worstY = y;
            ++compared;
        }
    std::printf("[ measured ] V̄ under a slab: worst |GPU − CPU| %.2e over %d pixels (at %d, %d)\n", worst, compared, worstX, worstY);
    EXPECT_GT(compared, 30);
    EXPECT_LE(worst, 1e-2);
}

TEST(StylizerVolume, SkippingEmptyBricksChangesNothing) {
    VOLSTYLE_REQUIRE_GL();
    // A blob in a 40³ grid (5³ bricks, most empty) against the same blob over a floor of 1e-30
    // (no brick empty: every midpoint sampled): the frames and V̄ agree.
    StylizerScene scene = forestWithBlobBox();
    Stylizer stylizer(test::device());
    GpuVolume blobOnly(grid(40, blob)), blobOverAFloor(grid(40, [](int i, int j, int k, int n) { return 1e-30 + blob(i, j, k, n); }));
    const StylizedFrame sparse = stylizer.render(scene, {}, &blobOnly);
    const StylizedFrame dense = stylizer.render(scene, {}, &blobOverAFloor);
    const double frame = test::maxAbsDifference(sparse.frame, dense.frame), scattering = test::maxAbsDifference(sparse.scattering, dense.scattering);
    double peak = 0;
    for (float x : sparse.scattering.rgba) peak = std::max(peak, double(x));
    std::printf("[ measured ] empty bricks skipped vs every midpoint: frame %.2e, scattering %.2e (peak %.3f)\n", frame, scattering, peak);
    EXPECT_GT(peak, 0.01) << "the blob scatters";
    EXPECT_LE(frame, 5e-5);  // float sums in another order (peak 1)
    EXPECT_LE(scattering, 5e-5);
}

TEST(StylizerVolume, ASparseVolumeIsItsMeanOverBlocksWhoseSideTheBudgetSets) {
    VOLSTYLE_REQUIRE_GL();
    // Issue #39: a sparse volume's medium is read through its bricks. Voxel for voxel while the box
    // fits the budget: the same frame as the dense volume. Over it: the mean over blocks of f³
    // voxels, which is the frame of a dense volume averaged over the same blocks on the CPU.
    EXPECT_EQ(stylizerMediumBlock({1024, 512, 1024}, int64_t(256) * 256 * 256), 4);
    EXPECT_EQ(stylizerMediumBlock({32, 32, 32}, 32 * 32 * 32), 1);
    EXPECT_EQ(stylizerMediumBlock({32, 32, 32}, 16 * 16 * 16), 2);
    EXPECT_EQ(stylizerMediumBlock({33, 32, 32}, 16 * 16 * 16), 3);  // 17 × 16 × 16 is over: blocks of 3
    StylizerScene scene = forestWithBlobBox();
    Stylizer stylizer(test::device());
    const Volume dense = grid(32, blob);
    const Volume sparse = dense.toSparse({3, 5, 1});  // bricks not aligned with the blocks
    ASSERT_TRUE(sparse.isSparse());
    ASSERT_LT(sparse.bricks()->activeBricks(), size_t(64)) << "most bricks of the blob's box are empty";
    GpuVolume denseGpu(dense), sparseGpu(sparse);
    const StylizedFrame a = stylizer.render(scene, {}, &denseGpu), b = stylizer.render(scene, {}, &sparseGpu);
    const double voxelForVoxel = test::maxAbsDifference(a.frame, b.frame);
    double peak = 0;
    for (float x : a.scattering.rgba) peak = std::max(peak, double(x));
    EXPECT_GT(peak, 0.01) << "the blob scatters";
    EXPECT_LE(voxelForVoxel, 1e-6);

    Volume halved({16, 16, 16}, unitBoxWorldFromIndex({16, 16, 16}));
    for (int k = 0; k < 16; ++k)
        for (int j = 0; j < 16; ++j)
            for (int i = 0; i < 16; ++i) {
                double sum = 0;
                for (int c = 0; c < 8; ++c) sum += dense.extinctionAt(2 * i + (c & 1), 2 * j + (c >> 1 & 1), 2 * k + (c >> 2)).x;
                const float m = float(sum / 8);
                halved.setExtinction(i, j, k, {m, m, m});
            }
    scene.volume->maxSparseMediumVoxels = 16 * 16 * 16;
    GpuVolume halvedGpu(halved);
    const StylizedFrame c = stylizer.render(scene, {}, &halvedGpu), d = stylizer.render(scene, {}, &sparseGpu);
    const double blocks = test::maxAbsDifference(c.frame, d.frame), fromFull = test::maxAbsDifference(a.frame, d.frame);
    std::printf("[ measured ] sparse medium vs dense: voxel for voxel %.2e; blocks of 2³ vs the CPU's block means %.2e "
                "(and vs full resolution %.2e)\n",
                voxelForVoxel, blocks, fromFull);
    EXPECT_LE(blocks, 1e-5);  // float sums in another order
    EXPECT_GT(fromFull, 10 * blocks) << "the budget did coarsen the medium";
}

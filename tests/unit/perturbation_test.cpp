// The perturbation field on the host (core/translucent/perturbation.h): deterministic noise in
// [0, 1], the identity when off, and a displaced field whose statistics stay within bounds.
#include <gtest/gtest.h>

#include <cmath>

#include "../common/stamped_cloud.h"
#include "core/translucent/perturbation.h"

using namespace volstyle;
using namespace volstyle::core;

TEST(Perturbation, NoiseIsDeterministicAndInRange) {
    const std::vector<float> a = noiseTexels(3), b = noiseTexels(3), c = noiseTexels(4);
    ASSERT_EQ(a.size(), size_t(kNoiseSize) * kNoiseSize * kNoiseSize * 4);
    EXPECT_EQ(a, b);
    EXPECT_NE(a, c);
    for (float x : a) ASSERT_TRUE(x >= 0 && x <= 1);
}

TEST(Perturbation, OffIsTheIdentityAndOnKeepsTheStatisticsWithinBounds) {
    const Volume cloud = test::thinCloud(24);
    Perturbation p;
    EXPECT_EQ(perturbVolume(cloud, p).extinction(), cloud.extinction());  // amplitude 0: exactly the volume
    p.amplitude = 1.5;
    p.seed = 5;
    const Volume moved = perturbVolume(cloud, p);
    const PerturbationField field(p, cloud.dims());
    double meanBefore = 0, meanAfter = 0, largest = 0;
    size_t supportBefore = 0, supportAfter = 0, outside = 0;
    const Int3 n = cloud.dims();
    // Support of the original dilated by ceil(amplitude) + 1 (trilinear reach).
    auto nearSupport = [&](int i, int j, int k) {
        const int r = int(std::ceil(p.amplitude)) + 1;
        for (int dk = -r; dk <= r; ++dk)
            for (int dj = -r; dj <= r; ++dj)
                for (int di = -r; di <= r; ++di) {
                    const int x = std::clamp(i + di, 0, n.x - 1), y = std::clamp(j + dj, 0, n.y - 1), z = std::clamp(k + dk, 0, n.z - 1);
                    if (cloud.extinction()[3 * cloud.index(x, y, z)] > 0) return true;
                }
        return false;
    };
    for (int k = 0; k < n.z; ++k)
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
                const double before = cloud.extinction()[3 * cloud.index(i, j, k)], after = moved.extinction()[3 * cloud.index(i, j, k)];
                meanBefore += before, meanAfter += after;
                supportBefore += before > 0, supportAfter += after > 0;
                if (after > 0 && !nearSupport(i, j, k)) ++outside;
                largest = std::max(largest, length(field.displacement({double(i), double(j), double(k)})));
            }
    std::printf("[ measured ] perturbation 1.5 voxels: mean extinction %.4f -> %.4f, support %zu -> %zu voxels, largest displacement %.3f\n",
                meanBefore / double(cloud.voxelCount()), meanAfter / double(cloud.voxelCount()), supportBefore, supportAfter, largest);
    EXPECT_LE(largest, p.amplitude * std::sqrt(3.0) + 1e-9);  // each axis within ±amplitude
    EXPECT_GT(largest, 0.3 * p.amplitude);
    EXPECT_NEAR(meanAfter, meanBefore, 0.1 * meanBefore);    // density moves, it is not made
    EXPECT_EQ(outside, 0u);                                   // nothing appears beyond the reach
    // The support may widen (trilinear reads bleed a voxel) but only within that reach, and it keeps
    // most of its voxels.
    EXPECT_GE(double(supportAfter), 0.8 * double(supportBefore));
}

TEST(Perturbation, ASparseVolumeIsBakedAsTheDenseOneWithinBricksGrownByTheReach) {
    // Issue #39: a small ball in a 48³ box, stored as bricks off the dense lattice, moved by up to
    // 9 voxels a side: the baked bricks hold the dense bake's values, bit for bit, and every voxel
    // the dense bake made non-zero lies in them.
    Volume dense({48, 48, 48}, Mat4::identity());
    auto& e = dense.ensureEmission();
    for (int k = 0; k < 48; ++k)
        for (int j = 0; j < 48; ++j)
            for (int i = 0; i < 48; ++i) {
                const double r = std::hypot(i - 20.0, j - 26.0, k - 23.0);
                if (r >= 6) continue;
                const float s = float(2 * (1 - r / 6));
                dense.setExtinction(i, j, k, {s, 0.5f * s, s});
                e[3 * dense.index(i, j, k)] = s;
            }
    const Volume sparse = dense.toSparse({3, 5, 1});
    ASSERT_TRUE(sparse.isSparse());
    Perturbation p;
    p.amplitude = 9;
    p.propertyAmplitude = 0.3;
    p.seed = 7;
    const Volume a = perturbVolume(dense, p), b = perturbVolume(sparse, p);
    ASSERT_TRUE(b.isSparse());
    EXPECT_GT(b.bricks()->activeBricks(), sparse.bricks()->activeBricks());
    EXPECT_LT(b.bricks()->activeBricks(), size_t(b.bricks()->brickDims().volume())) << "bricks out of reach stay inactive";
    const Volume back = b.toDense();
    EXPECT_EQ(back.extinction(), a.extinction());
    EXPECT_EQ(back.emission(), a.emission());
    size_t moved = 0;
    for (size_t i = 0; i < a.voxelCount(); ++i) moved += a.extinction()[3 * i] != dense.extinction()[3 * i];
    std::printf("[ measured ] sparse bake: %zu -> %zu bricks, %zu voxels changed, equal to the dense bake\n", sparse.bricks()->activeBricks(),
                b.bricks()->activeBricks(), moved);
    EXPECT_GT(moved, 500u);
}

// Hole filling on the shadow map (issue #11): the GPU closing (van Herk / Gil-Werman running
// extrema) against brute force on random depth maps, for boxes and discs of radius 1–32.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <gtest/gtest.h>

#include <random>

#include "core/stylize/morphology.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// Random occluders: blobs of depths in [0.2, 0.8] with holes, the rest 1 (nothing).
std::vector<float> randomMap(int n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<float> d(size_t(n) * n, 1.0f);
    for (float& v : d)
        if (rng() % 100 < 55) v = 0.2f + 0.6f * float(rng() % 1000) / 1000.0f;
    return d;
}

}  // namespace

TEST(Morphology, DiscRowsAreTheDisc) {
    EXPECT_EQ(discHalfWidth(5, 0), 5);
    EXPECT_EQ(discHalfWidth(5, 3), 4);
    EXPECT_EQ(discHalfWidth(5, 4), 3);
    EXPECT_EQ(discHalfWidth(5, 5), 0);
    EXPECT_EQ(discHalfWidth(1, 1), 0);
}

TEST(Morphology, LargeDiscsAreOctagonsCloseToTheDisc) {
    // From radius 5 on a disc is the octagon of four segments (morphology.h): its outline within
    // 0.09 r (+ a texel of rounding) of the circle, symmetric, as wide as the disc on the axes,
    // and convex.
    for (int r : {4, 5, 8, 16, 32, 64}) {
        double worst = 0;
        EXPECT_EQ(elementHalfWidth(r, 0, MorphShape::Disc), r);
        EXPECT_EQ(elementHalfWidth(r, r + 1, MorphShape::Disc), -1);
        int previous = r;
        for (int dy = 0; dy <= r; ++dy) {
            const int w = elementHalfWidth(r, dy, MorphShape::Disc);
            EXPECT_EQ(w, elementHalfWidth(r, -dy, MorphShape::Disc));
            if (r <= kExactDiscRadius) {
                EXPECT_EQ(w, discHalfWidth(r, dy));
            }
            worst = std::max(worst, std::abs(std::hypot(w, dy) - r));
            EXPECT_LE(w, previous) << "convex: rows shrink away from the centre";
            previous = w;
        }
        EXPECT_LE(worst, 0.09 * r + 1) << "r " << r;
        if (r == 32) std::cout << "[ measured ] octagon of radius 32: outline within " << worst << " texels of the circle\n";
    }
}

TEST(Morphology, GpuClosingEqualsBruteForceForBoxesAndDiscs) {
    VOLSTYLE_REQUIRE_GL();
    for (MorphShape shape : {MorphShape::Box, MorphShape::Disc})
        for (int r : {1, 2, 3, 4, 5, 7, 16, 32}) {
            const int n = r >= 16 ? 48 + 2 * r : 48;
            std::vector<float> map = randomMap(n, uint32_t(7 * r + (shape == MorphShape::Disc)));
            if (shape == MorphShape::Disc && r > kExactDiscRadius) {
                // The octagon's diagonal passes route through texels off the map (empty), so it is
                // exact where occluders keep the margin of r texels the stylizer leaves
                // (morphology.h); boxes and small discs are exact up to the border.
                for (int y = 0; y < n; ++y)
                    for (int x = 0; x < n; ++x)
                        if (std::min({x, y, n - 1 - x, n - 1 - y}) < r) map[size_t(y) * n + x] = 1;
            }
            const std::vector<float> gpu = closingOnGpu(test::device(), map, n, r, shape);
            const std::vector<float> ref = closingReference(map, n, r, shape);
            size_t differ = 0;
            for (size_t i = 0; i < ref.size(); ++i) differ += gpu[i] != ref[i];
            EXPECT_EQ(differ, 0u) << (shape == MorphShape::Box ? "box" : "disc") << " radius " << r;
        }
}

TEST(Morphology, ClosingFillsHolesSmallerThanTheElementAndKeepsTheOutline) {
    VOLSTYLE_REQUIRE_GL();
    const int n = 64;
    std::vector<float> map(size_t(n) * n, 1.0f);
    for (int y = 16; y < 48; ++y)
        for (int x = 16; x < 48; ++x) map[size_t(y) * n + x] = 0.5f;  // an occluder
    for (int y = 30; y < 33; ++y)
        for (int x = 30; x < 33; ++x) map[size_t(y) * n + x] = 1.0f;  // a 3×3 hole in it
    const std::vector<float> closed = closingOnGpu(test::device(), map, n, 2, MorphShape::Box);
    EXPECT_EQ(closed[size_t(31) * n + 31], 0.5f) << "the hole is filled";
    EXPECT_EQ(closed[size_t(10) * n + 10], 1.0f) << "outside stays empty";
    EXPECT_EQ(closed[size_t(16) * n + 16], 0.5f) << "the corner stays";
    EXPECT_EQ(closed[size_t(15) * n + 16], 1.0f) << "and does not grow";
}

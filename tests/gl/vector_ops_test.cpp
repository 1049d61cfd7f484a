// The solver's vector kernels against float64 sums on the host: the per-view dots of every
// iteration's RMS come from one dispatch (VectorOps::dots, issue #40) and equal each range's own
// dot, over all elements and over a support's list.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "core/solve/gpu_vector.h"
#include "gl_test_env.h"

using namespace volstyle;
using namespace volstyle::core;

TEST(VectorOps, TheDotsOfManyRangesInOneDispatchAreEachRangesDot) {
    VOLSTYLE_REQUIRE_GL();
    const size_t n = 5000;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> xs(4 * n), ys(4 * n);
    for (size_t i = 0; i < 4 * n; ++i) xs[i] = u(rng), ys[i] = u(rng);
    GpuVector x(n, "x"), y(n, "y");
    x.upload(xs), y.upload(ys);
    const std::vector<Range> ranges = {{0, 1200}, {1200, 3000}, {4200, 800}, {10, 0}, {4990, 100}};
    std::vector<uint32_t> everyThird;
    for (uint32_t i = 0; i < n; i += 3) everyThird.push_back(i);
    VectorOps ops(test::device());
    for (bool indexed : {false, true}) {
        std::shared_ptr<const Support> support = indexed ? std::make_shared<const Support>(everyThird) : nullptr;
        y.setSupport(support);
        const std::vector<Vec3d> got = ops.dots(x, y, ranges);
        ASSERT_EQ(got.size(), ranges.size());
        for (size_t r = 0; r < ranges.size(); ++r) {
            Vec3d want(0.0);
            for (size_t e = ranges[r].first; e < std::min(n, ranges[r].first + ranges[r].count); ++e) {
                if (indexed && e % 3 != 0) continue;
                for (int c = 0; c < 3; ++c) want[c] += double(xs[4 * e + size_t(c)]) * double(ys[4 * e + size_t(c)]);
            }
            const Vec3d one = ops.dot(x, y, ranges[r]);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(got[r][c], want[c], 1e-9 * (1 + std::abs(want[c]))) << "range " << r << (indexed ? " (indexed)" : "");
                EXPECT_NEAR(one[c], want[c], 1e-9 * (1 + std::abs(want[c])));
            }
        }
    }
}

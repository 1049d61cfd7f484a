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
    for (bool onHost : {false, true}) {  // vector_ops.comp, and the host's kernels (host_vector_ops.h)
        const size_t n = 5000;
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        std::vector<float> xs(4 * n), ys(4 * n);
        for (size_t i = 0; i < 4 * n; ++i) xs[i] = u(rng), ys[i] = u(rng);
        GpuVector x(n, "x", onHost), y(n, "y", onHost);
        x.upload(xs), y.upload(ys);
        const std::vector<Range> ranges = {{0, 1200}, {1200, 3000}, {4200, 800}, {10, 0}, {4990, 100}};
        std::vector<uint32_t> everyThird;
        for (uint32_t i = 0; i < n; i += 3) everyThird.push_back(i);
        VectorOps ops(test::device());
        ops.setOnHost(onHost);
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
}

namespace {

/// Every kernel of vector_ops.comp once, on vectors the host can map, by `ops` as it is set: the
/// vectors each kernel wrote and the reductions' values, in order.
struct KernelResults {
    std::vector<std::vector<float>> vectors;
    std::vector<double> reductions;
};

KernelResults runEveryKernel(VectorOps& ops, bool indexed) {
    const Int3 dims{6, 5, 4};
    const size_t block = size_t(dims.volume()), n = 2 * block;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.5f, 1.5f);
    auto randomValues = [&](bool atBounds) {
        std::vector<float> v(4 * n);
        for (size_t i = 0; i < v.size(); ++i) v[i] = atBounds && i % 7 == 0 ? float(i % 2) : u(rng);  // some exactly at 0 and 1
        return v;
    };
    std::vector<float> hull(4 * n, 0.0f);
    for (size_t i = 0; i < n; ++i) hull[4 * i] = hull[4 * i + 1] = hull[4 * i + 2] = i % 10 < 7 ? 1.0f : 0.0f;
    GpuVector x(n, "x", true), y(n, "y", true), z(n, "z", true), h(n, "hull", true), out(n, "out", true);
    x.upload(randomValues(true)), y.upload(randomValues(false)), z.upload(randomValues(false)), h.upload(hull);
    std::vector<uint32_t> list;
    for (uint32_t i = 0; i < n; i += 3) list.push_back(i);
    if (indexed) y.setSupport(std::make_shared<const Support>(list));
    Bounds bounds;
    bounds.lower[0] = 0.0f, bounds.upper[0] = 3e38f, bounds.lower[1] = 0.0f, bounds.upper[1] = 1.0f;
    bounds.blockSize = block;
    KernelResults r;
    auto keep = [&](const GpuVector& v) { r.vectors.push_back(v.download()); };
    auto keep3 = [&](const Vec3d& v) { r.reductions.insert(r.reductions.end(), {v.x, v.y, v.z}); };
    ops.axpy(Vec3d(0.5, -2.0, 3.0), x, y, {17, 150}), keep(y);
    ops.xpby(z, Vec3d(0.25, 1.5, -1.0), y), keep(y);
    ops.multiply(z, y, {0, 200}), keep(y);
    keep3(ops.dot(x, y)), keep3(ops.dot(x, y, {30, 90}));
    for (const Vec3d& d : ops.dots(x, y, {{0, 100}, {100, 140}, {5, 0}})) keep3(d);
    ops.laplacian(0.7, x, h, dims, out), keep(out);
    ops.laplacian(-1.3, z, h, dims, out, {block, block}), keep(out);
    out.setSupport(y.support() ? std::make_shared<const Support>(list) : nullptr);  // the listed cells only
    out.fill(5.0f);
    ops.laplacian(0.3, z, h, dims, out), keep(out);
    keep3(ops.dot(y, y));  // one vector as both operands: mapped once
    ops.freeSet(x, y, bounds), keep(y);
    keep3(ops.maxStep(x, y, bounds));
    keep3(ops.maxChange(x, y, z));
    ops.clamp(x, bounds), keep(x);
    return r;
}

}  // namespace

TEST(VectorOps, EveryKernelOnTheHostIsTheShaders) {
    VOLSTYLE_REQUIRE_GL();
    // Issue #40: on a CPU rasterizer the kernels run on the host (host_vector_ops.h), on a GPU in
    // vector_ops.comp; CI runs on the first, so both are run here on the same inputs (values
    // exactly at the bounds included) and must agree: element-wise updates to float rounding,
    // reductions (float64) to 1e-12.
    for (bool indexed : {false, true}) {
        VectorOps shader(test::device()), host(test::device());
        shader.setOnHost(false), host.setOnHost(true);
        const KernelResults want = runEveryKernel(shader, indexed), got = runEveryKernel(host, indexed);
        ASSERT_EQ(want.vectors.size(), got.vectors.size());
        for (size_t k = 0; k < want.vectors.size(); ++k)
            for (size_t i = 0; i < want.vectors[k].size(); ++i)
                ASSERT_NEAR(got.vectors[k][i], want.vectors[k][i], 2e-6f * (1.0f + std::abs(want.vectors[k][i])))
                    << "vector " << k << " value " << i << (indexed ? " (indexed)" : "");
        ASSERT_EQ(want.reductions.size(), got.reductions.size());
        for (size_t k = 0; k < want.reductions.size(); ++k)
            EXPECT_NEAR(got.reductions[k], want.reductions[k], 1e-12 * (1.0 + std::abs(want.reductions[k]))) << "reduction " << k;
    }
}

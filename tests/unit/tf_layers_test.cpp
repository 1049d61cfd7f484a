// Transfer-function layers and their diffusion (core/stylize/tf_layers.h, issue #15): the membrane
// solve against an independent dense solve of the same discrete problem, one constraint uniform,
// two on a row linear, and the layer stack's blending.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "core/base/errors.h"
#include "core/stylize/tf_layers.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// The same problem assembled densely over every texel and solved by Gaussian elimination with
/// partial pivoting: pinned texels u = value, others deg·u − Σ neighbours = 0.
std::vector<double> denseSolve(const std::vector<TfConstraint>& cs, int w, int h, int channel) {
    const int n = w * h;
    std::vector<std::vector<double>> A(size_t(n), std::vector<double>(size_t(n) + 1, 0.0));
    std::vector<double> sum(size_t(n), 0.0);
    std::vector<int> count(size_t(n), 0);
    for (const auto& c : cs) {  // the texels a bilinear lookup at the constraint reads with weight > 0
        const double fx = std::clamp(c.vBar * w - 0.5, 0.0, w - 1.0), fy = std::clamp((1 - c.depth) * h - 0.5, 0.0, h - 1.0);
        std::set<int> texels;
        for (int y : {int(std::floor(fy)), int(std::ceil(fy))})
            for (int x : {int(std::floor(fx)), int(std::ceil(fx))}) texels.insert(y * w + x);
        const double v = channel == 0 ? c.colour.x : channel == 1 ? c.colour.y : channel == 2 ? c.colour.z : c.alpha;
        for (int t : texels) sum[size_t(t)] += v, ++count[size_t(t)];
    }
    for (int t = 0; t < n; ++t) {
        auto& row = A[size_t(t)];
        if (count[size_t(t)]) {
            row[size_t(t)] = 1, row[size_t(n)] = sum[size_t(t)] / count[size_t(t)];
            continue;
        }
        const int x = t % w, y = t / w;
        for (auto [dx, dy] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            row[size_t(t)] += 1, row[size_t(ny * w + nx)] -= 1;
        }
    }
    for (int col = 0; col < n; ++col) {
        int pivot = col;
        for (int r = col + 1; r < n; ++r)
            if (std::abs(A[size_t(r)][size_t(col)]) > std::abs(A[size_t(pivot)][size_t(col)])) pivot = r;
        std::swap(A[size_t(col)], A[size_t(pivot)]);
        for (int r = 0; r < n; ++r) {
            if (r == col) continue;
            const double f = A[size_t(r)][size_t(col)] / A[size_t(col)][size_t(col)];
            if (f == 0) continue;
            for (int k = col; k <= n; ++k) A[size_t(r)][size_t(k)] -= f * A[size_t(col)][size_t(k)];
        }
    }
    std::vector<double> u(static_cast<size_t>(n), 0.0);
    for (int t = 0; t < n; ++t) u[size_t(t)] = A[size_t(t)][size_t(n)] / A[size_t(t)][size_t(t)];
    return u;
}

}  // namespace

TEST(TfLayers, DiffusionMatchesADenseSolve) {
    // 9×7: CG with Jacobi; 20×16: CG with the multigrid preconditioner.
    for (auto [w, h, k] : {std::tuple{9, 7, 4}, std::tuple{20, 16, 5}}) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<TfConstraint> cs;
    for (int i = 0; i < k; ++i) cs.push_back({u(rng), u(rng), {u(rng), u(rng), u(rng)}, u(rng)});
    std::vector<double> alpha;
    int iterations = 0;
    double residual = 0;
    const std::vector<Vec3d> c = diffuseConstraints(cs, w, h, alpha, &iterations, &residual);
    double worst = 0;
    for (int ch = 0; ch < 4; ++ch) {
        const std::vector<double> want = denseSolve(cs, w, h, ch);
        for (size_t t = 0; t < want.size(); ++t) worst = std::max(worst, std::abs((ch < 3 ? c[t][ch] : alpha[t]) - want[t]));
    }
    std::printf("[ measured ] diffusion on %dx%d with %d constraints: %d CG iterations, residual %.2e, worst difference from the dense solve %.2e\n",
                w, h, k, iterations, residual, worst);
    EXPECT_LE(worst, 1e-4);
    }
}

TEST(TfLayers, OneConstraintIsUniformAndTwoOnARowAreLinear) {
    std::vector<double> alpha;
    const std::vector<Vec3d> one = diffuseConstraints({{0.3, 0.6, {0.2, 0.5, 0.9}, 0.7}}, 16, 12, alpha);
    for (size_t t = 0; t < one.size(); ++t) {
        ASSERT_EQ(one[t], Vec3d(0.2, 0.5, 0.9));
        ASSERT_EQ(alpha[t], 0.7);
    }
    // A one-row TF (d only one value): two constraints give a ramp between them, flat beyond.
    const int w = 32;
    const std::vector<Vec3d> two = diffuseConstraints({{(4 + 0.5) / w, 0.5, {0, 0, 0}, 1}, {(27 + 0.5) / w, 0.5, {1, 0.5, 0}, 1}}, w, 1, alpha);
    for (int x = 0; x < w; ++x) {
        const double t = std::clamp((x - 4) / 23.0, 0.0, 1.0);
        EXPECT_NEAR(two[size_t(x)].x, t, 1e-9) << x;
        EXPECT_NEAR(two[size_t(x)].y, 0.5 * t, 1e-9) << x;
    }
}

TEST(TfLayers, TheStackBlendsBottomToTop) {
    TfLayer base;  // opaque white
    base.solid = {0, 0, {1, 1, 1}, 1};
    TfLayer ramp;  // red to blue along V̄, multiplied
    ramp.kind = TfLayerKind::Gradient;
    ramp.blend = TfBlend::Multiply;
    ramp.from = {0, 0.5, {1, 0, 0}, 1};
    ramp.to = {1, 0.5, {0, 0, 1}, 1};
    TfLayer spot;  // half-transparent green diffusion
    spot.kind = TfLayerKind::Diffusion;
    spot.opacity = 0.5;
    spot.constraints = {{0.5, 0.5, {0, 1, 0}, 1}};
    TfCompileStats stats;
    const Image tf = compileTfLayers({base, ramp, spot}, 8, 4, &stats);
    // Left column: red from the ramp, then half of it green.
    const float* left = tf.pixel(0, 1);
    EXPECT_NEAR(left[0], (1 - 1.0 / 16) * 0.5, 1e-6);  // the ramp at V̄ = 1/16, halved
    EXPECT_NEAR(left[1], 0.5, 1e-6);
    EXPECT_NEAR(left[3], 1.0, 1e-6);
    TfLayer noImage;
    noImage.kind = TfLayerKind::Image;
    EXPECT_THROW(compileTfLayers({noImage}, 8, 4), InvalidArgument);
    TfLayer bad;
    bad.solid.colour = {2, 0, 0};
    EXPECT_THROW(compileTfLayers({bad}, 8, 4), InvalidArgument);
}

TEST(TfLayers, TheTfAtAConstraintIsItsColour) {
    // Constraints between texel centres pin their bilinear footprint, so the lookup the stylizer
    // makes at exactly (V̄, d) reads their colour and alpha (straight, not premultiplied).
    TfLayer layer;
    layer.kind = TfLayerKind::Diffusion;
    layer.constraints = {{0.137, 0.81, {0.9, 0.2, 0.1}, 1}, {0.71, 0.23, {0.1, 0.7, 0.3}, 0.8}, {0.45, 0.52, {0.5, 0.5, 0.9}, 0.6}};
    const Image tf = compileTfLayers({layer}, 37, 23);
    for (const TfConstraint& c : layer.constraints) {
        const auto F = sampleTransferFunction(tf, c.vBar, c.depth);
        for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(F[size_t(ch)], c.colour[ch], 1e-5) << c.vBar;
        EXPECT_NEAR(F[3], c.alpha, 1e-5);
    }
}

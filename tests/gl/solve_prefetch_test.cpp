// Work ahead (issue #40): the views' bound renders and rows of W made before a solve
// (core/solve/solve_prefetch.h, what the server does while the artist paints) must be exactly what
// the solve would make: a solve that finds them lands where a cold one does, bit for bit, whatever
// unknowns it picks and whichever pixels its paint weights, and a prefetch that stops between
// chunks keeps what it finished and loses nothing else.
#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <atomic>

#include "core/render/renderer.h"
#include "core/solve/host_columns.h"
#include "core/solve/projector.h"
#include "core/solve/solve_cache.h"
#include "core/solve/solve_prefetch.h"
#include "gl_test_env.h"
#include "stamped_problem.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// The views as the server knows them before any paint: cameras, no targets.
std::vector<SolveView> unpainted(const std::vector<SolveView>& views) {
    std::vector<SolveView> out;
    for (const SolveView& v : views) out.push_back({v.name, v.camera, Image(), std::nullopt, v.background});
    return out;
}

void expectSameIterates(const SolveReport& a, const SolveReport& b) {
    ASSERT_EQ(a.objectiveHistory.size(), b.objectiveHistory.size());
    for (size_t i = 0; i < a.objectiveHistory.size(); ++i) EXPECT_EQ(a.objectiveHistory[i], b.objectiveHistory[i]) << "iteration " << i;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(a.finalRms[size_t(c)], b.finalRms[size_t(c)]);
}

template <typename T>
std::vector<T> contents(const gl::Buffer& b, size_t count) {
    std::vector<T> out(count);
    if (count) glGetNamedBufferSubData(b.id(), 0, GLsizeiptr(count * sizeof(T)), out.data());
    return out;
}

/// Every start, index and weight of two views' rows and columns, equal.
void expectSameRows(const SparseRows& a, const SparseRows& b) {
    ASSERT_EQ(a.rows, b.rows);
    ASSERT_EQ(a.columns, b.columns);
    ASSERT_EQ(a.entries, b.entries);
    ASSERT_EQ(a.channels, b.channels);
    const size_t E = a.entries, ch = size_t(a.channels);
    EXPECT_EQ(contents<uint32_t>(a.rowStart, a.rows + 1), contents<uint32_t>(b.rowStart, b.rows + 1));
    EXPECT_EQ(contents<uint32_t>(a.rowIndex, E), contents<uint32_t>(b.rowIndex, E));
    EXPECT_EQ(contents<float>(a.rowWeight, E * ch), contents<float>(b.rowWeight, E * ch));
    EXPECT_EQ(contents<uint32_t>(a.colStart, a.columns + 1), contents<uint32_t>(b.colStart, b.columns + 1));
    EXPECT_EQ(contents<uint32_t>(a.colIndex, E), contents<uint32_t>(b.colIndex, E));
    EXPECT_EQ(contents<float>(a.colWeight, E * ch), contents<float>(b.colWeight, E * ch));
}

/// One view's rows as the solver writes them: `mask` 1 where a pixel has weight (null: every pixel).
std::shared_ptr<const SparseRows> rowsOf(GpuVolume& gpu, const Camera& camera, Unknown u, const std::vector<uint8_t>& mask,
                                         const WorkBudget* budget = nullptr) {
    Projector W(test::device(), gpu, defaultLighting(), u, BasisType::Trilinear, gpu.dims(), 0.5, false);
    W.setMergeViews(false);
    W.setColumnsOnHost(true);  // the host reads them (a CPU rasterizer's default; forced on a GPU too)
    W.setBudget(budget);
    W.addView(camera);
    GpuVector weights(W.pixelCount(), "weights");
    std::vector<float> w(4 * W.pixelCount(), 0.0f);
    for (size_t p = 0; p < W.pixelCount(); ++p) w[4 * p] = w[4 * p + 1] = w[4 * p + 2] = mask[p] ? 1.0f : 0.0f;
    weights.upload(w);
    W.cacheRows(size_t(1) << 30, 3, &weights);
    return W.rowsOf(0);
}

}  // namespace

TEST(SolvePrefetch, ASolveFromWorkDoneAheadIsTheColdSolve) {
    VOLSTYLE_REQUIRE_GL();
    const test::Problem p = test::stampedProblem();  // weights: the targets' alpha, so some pixels have none
    const size_t V = p.views.size();
    SolveOptions opt = test::plainOptions(5);
    opt.localResolve = false;
    SolveCache cache;
    const PrefetchReport ahead = prefetchSolve(test::device(), p.plain, defaultLighting(), unpainted(p.views), opt, cache);
    EXPECT_EQ(ahead.viewsRendered, int(V));
    EXPECT_EQ(ahead.viewsFound, 0);
    const int rowsAhead = solverKernelsOnHost(test::device()) ? int(V) : 0;  // (a GPU writes its rows at solve time)
    EXPECT_EQ(ahead.rowsWritten, rowsAhead);
    EXPECT_EQ(cache.entries(), V + size_t(rowsAhead));
    const PrefetchReport again = prefetchSolve(test::device(), p.plain, defaultLighting(), unpainted(p.views), opt, cache);
    EXPECT_EQ(again.viewsRendered + again.rowsWritten, 0) << "the same volume again: nothing to make";
    EXPECT_EQ(again.viewsFound, int(V));

    // Made ahead for emission: its renders (of exactly this volume) serve emission + albedo too,
    // its rows (for every pixel) serve emission whatever the weights.
    for (Unknown u : {Unknown::Emission, Unknown::EmissionAlbedo}) {
        SolveOptions o = opt;
        o.unknown = u;
        const size_t hits = cache.hits();
        const SolveReport warm = Solver(test::device(), p.plain, defaultLighting(), p.views, o, &cache).run().report;
        EXPECT_EQ(cache.hits() - hits, V + (u == Unknown::Emission ? size_t(rowsAhead) : 0)) << "each view's renders (and, for emission, rows) found";
        const SolveReport cold = Solver(test::device(), p.plain, defaultLighting(), p.views, o).run().report;
        expectSameIterates(warm, cold);
        EXPECT_EQ(warm.writtenViews, u == Unknown::Emission && rowsAhead ? 0u : V) << "views whose rows this solve wrote";
        EXPECT_EQ(cold.writtenViews, V);
    }
}

TEST(SolvePrefetch, RowsForEveryPixelRestrictedToThePaintedOnesAreTheRowsWrittenForThose) {
    VOLSTYLE_REQUIRE_GL();
    // The rows work ahead writes before the paint exists, cut down to the pixels the paint
    // weights (restrictRowsOnHost), entry for entry the rows a solve writes for those pixels —
    // written in chunks of eight rows that could stop, as the server writes them.
    const test::Problem p = test::stampedProblem();
    GpuVolume gpu(p.plain);
    const Camera& c = p.views[1].camera;
    const size_t P = size_t(c.width) * c.height;
    const std::atomic<bool> never{false};
    const WorkBudget chunked = WorkBudget(0, &never).withFinerChunks(1 << 12);
    for (Unknown u : {Unknown::Emission, Unknown::EmissionAlbedo}) {
        const auto all = rowsOf(gpu, c, u, std::vector<uint8_t>(P, 1), &chunked);
        expectSameRows(*all, *rowsOf(gpu, c, u, std::vector<uint8_t>(P, 1)));
        std::vector<uint8_t> painted(P, 0);  // a stroke's disc, and every seventh pixel
        for (size_t i = 0; i < P; ++i) painted[i] = std::hypot(double(i % 32) - 12, double(i / 32) - 17) < 7 || i % 7 == 0;
        const auto cut = restrictRowsOnHost(all, painted);
        EXPECT_NE(cut, all) << "pixels with entries were left out";
        EXPECT_LT(cut->entries, all->entries);
        expectSameRows(*cut, *rowsOf(gpu, c, u, painted));
        // Leaving out only pixels whose rays meet no medium copies nothing.
        std::vector<uint8_t> seen(P, 0);
        const std::vector<uint32_t> start = contents<uint32_t>(all->rowStart, P + 1);
        size_t unseen = 0;
        for (size_t i = 0; i < P; ++i) seen[i] = start[i + 1] > start[i], unseen += !seen[i];
        ASSERT_GT(unseen, 0u) << "the test needs pixels beside the cloud";
        EXPECT_EQ(restrictRowsOnHost(all, seen), all);
    }
}

TEST(SolvePrefetch, ARenderInSmallChunksIsTheWholeRender) {
    VOLSTYLE_REQUIRE_GL();
    // The server's work ahead marches 2^12 pixels at a time so that a request waits little; the
    // pixels do not depend on how the image is cut.
    const test::Problem p = test::stampedProblem();
    GpuVolume gpu(p.plain);
    Renderer& r = test::sharedRenderer();
    const std::atomic<bool> never{false};
    Camera c = p.views[0].camera;
    c.width = 48, c.height = 40;  // rows that do not divide into the chunks
    const Image whole = r.render(gpu, c, defaultLighting());
    const Image chunked = r.render(gpu, c, defaultLighting(), RenderSettings(), nullptr, WorkBudget(0, &never).withFinerChunks(1 << 11));
    ASSERT_EQ(whole.rgba.size(), chunked.rgba.size());
    for (size_t i = 0; i < whole.rgba.size(); ++i) ASSERT_EQ(whole.rgba[i], chunked.rgba[i]) << "value " << i;
}

TEST(SolvePrefetch, APrefetchThatYieldsKeepsWhatItFinished) {
    VOLSTYLE_REQUIRE_GL();
    const test::Problem p = test::stampedProblem();
    const std::vector<SolveView> views = unpainted(p.views);
    SolveOptions opt = test::plainOptions(3);
    SolveCache cache;
    prefetchSolve(test::device(), p.plain, defaultLighting(), {views[0], views[1]}, opt, cache);
    ASSERT_EQ(cache.entries(), 4u) << "two views' renders and rows";
    // A request arrives (the GL thread raises the flag): the next view stops after its first chunk.
    const std::atomic<bool> yield{true};
    EXPECT_THROW(prefetchSolve(test::device(), p.plain, defaultLighting(), views, opt, cache, WorkBudget(0, &yield).withFinerChunks(1 << 12)),
                 Cancelled);
    EXPECT_EQ(cache.entries(), 4u) << "the finished views stay; the interrupted one left nothing";
    const PrefetchReport rest = prefetchSolve(test::device(), p.plain, defaultLighting(), views, opt, cache);
    EXPECT_EQ(rest.viewsFound, 2);
    EXPECT_EQ(rest.viewsRendered, 2);
    EXPECT_EQ(rest.rowsWritten, 2);
}

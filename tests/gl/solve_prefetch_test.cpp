// Work ahead (issue #40): the views' bound renders made before a solve (core/solve/solve_prefetch.h,
// what the server does while the artist paints) must be exactly what the solve would render: a
// solve that finds them lands where a cold one does, whatever unknowns it picks, and a prefetch
// that stops between chunks keeps what it finished and loses nothing else.
#include <gtest/gtest.h>

#include <atomic>

#include "core/render/renderer.h"
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

}  // namespace

TEST(SolvePrefetch, ASolveFromRendersMadeAheadIsTheColdSolveForAnyUnknowns) {
    VOLSTYLE_REQUIRE_GL();
    const test::Problem p = test::stampedProblem();
    const size_t V = p.views.size();
    SolveOptions opt = test::plainOptions(5);
    opt.localResolve = false;
    SolveCache cache;
    const PrefetchReport ahead = prefetchSolve(test::device(), p.plain, defaultLighting(), unpainted(p.views), opt, cache);
    EXPECT_EQ(ahead.viewsRendered, int(V));
    EXPECT_EQ(ahead.viewsFound, 0);
    EXPECT_EQ(cache.entries(), V);
    // The same volume again: nothing to render.
    const PrefetchReport again = prefetchSolve(test::device(), p.plain, defaultLighting(), unpainted(p.views), opt, cache);
    EXPECT_EQ(again.viewsRendered, 0);
    EXPECT_EQ(again.viewsFound, int(V));

    // Made for emission (the server's guess before a first solve), they serve emission + albedo too:
    // they are renders of exactly this volume. Bit for bit the renders a cold solve makes.
    for (Unknown u : {Unknown::Emission, Unknown::EmissionAlbedo}) {
        SolveOptions o = opt;
        o.unknown = u;
        const size_t hits = cache.hits();
        const SolveReport warm = Solver(test::device(), p.plain, defaultLighting(), p.views, o, &cache).run().report;
        EXPECT_EQ(cache.hits() - hits, V) << "each view's renders found, under the exact volume's key";
        const SolveReport cold = Solver(test::device(), p.plain, defaultLighting(), p.views, o).run().report;
        expectSameIterates(warm, cold);
    }
}

TEST(SolvePrefetch, ARenderInSmallChunksIsTheWholeRender) {
    VOLSTYLE_REQUIRE_GL();
    // The server's work ahead marches 2^14 pixels at a time so that a request waits little; the
    // pixels do not depend on how the image is cut.
    const test::Problem p = test::stampedProblem();
    GpuVolume gpu(p.plain);
    Renderer& r = test::sharedRenderer();
    const std::atomic<bool> never{false};
    Camera c = p.views[0].camera;
    c.width = 48, c.height = 40;  // rows that do not divide into the chunks
    const Image whole = r.render(gpu, c, defaultLighting());
    const Image chunked = r.render(gpu, c, defaultLighting(), RenderSettings(), nullptr, WorkBudget(0, &never).withChunksOf(100));
    ASSERT_EQ(whole.rgba.size(), chunked.rgba.size());
    for (size_t i = 0; i < whole.rgba.size(); ++i) ASSERT_EQ(whole.rgba[i], chunked.rgba[i]) << "value " << i;
}

TEST(SolvePrefetch, APrefetchThatYieldsKeepsTheViewsItFinished) {
    VOLSTYLE_REQUIRE_GL();
    const test::Problem p = test::stampedProblem();
    const std::vector<SolveView> views = unpainted(p.views);
    SolveOptions opt = test::plainOptions(3);
    SolveCache cache;
    prefetchSolve(test::device(), p.plain, defaultLighting(), {views[0], views[1]}, opt, cache);
    ASSERT_EQ(cache.entries(), 2u);
    // A request arrives (the GL thread raises the flag): the next view stops after its first chunk.
    const std::atomic<bool> yield{true};
    EXPECT_THROW(prefetchSolve(test::device(), p.plain, defaultLighting(), views, opt, cache, WorkBudget(0, &yield).withChunksOf(64)),
                 Cancelled);
    EXPECT_EQ(cache.entries(), 2u) << "the two finished views stay; the interrupted one left nothing";
    const PrefetchReport rest = prefetchSolve(test::device(), p.plain, defaultLighting(), views, opt, cache);
    EXPECT_EQ(rest.viewsFound, 2);
    EXPECT_EQ(rest.viewsRendered, 2);
}

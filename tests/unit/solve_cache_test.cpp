// What the solver's cache drops first (issue #40, core/solve/solve_cache.h): GreedyDual-Size,
// the entry that saves the fewest milliseconds per byte it holds, with recency through the
// clock. Checked with last-solve entries, which need no GL (their bytes: 4 per float held).
#include <gtest/gtest.h>

#include <memory>

#include "core/solve/solve_cache.h"

using namespace volstyle::core;

namespace {

std::shared_ptr<const LastSolve> floats(size_t n) {
    auto last = std::make_shared<LastSolve>();
    last->observations.assign(n, 0.0f);
    return last;
}

TEST(SolveCache, WhatSavesTheLeastPerByteGoesFirstNotTheOldest) {
    SolveCache cache(100);
    cache.putLastSolve("dear", floats(10), 100);  // 40 bytes that took 100 ms
    cache.putLastSolve("cheap", floats(10), 1);   // 40 bytes that took 1 ms
    cache.putLastSolve("new", floats(10), 50);    // over 100 bytes: "cheap" goes, though "dear" is older
    EXPECT_NE(cache.findLastSolve("dear"), nullptr);
    EXPECT_EQ(cache.findLastSolve("cheap"), nullptr);
    EXPECT_NE(cache.findLastSolve("new"), nullptr);
    EXPECT_EQ(cache.bytes(), 80u);
    // An entry worth less per byte than everything kept does not stay, even just put.
    cache.putLastSolve("bulky", floats(10), 0.5);
    EXPECT_EQ(cache.findLastSolve("bulky"), nullptr);
    EXPECT_NE(cache.findLastSolve("dear"), nullptr);
    EXPECT_NE(cache.findLastSolve("new"), nullptr);
}

TEST(SolveCache, AnEntryPutAgainKeepsWhatItCostAndUnusedOnesAgeOut) {
    SolveCache cache(100);
    cache.putLastSolve("kept", floats(10), 40);
    cache.putLastSolve("kept", floats(10), 0);  // a hit's put: the cost it was made at stays
    cache.putLastSolve("other", floats(10), 30);
    cache.putLastSolve("third", floats(10), 35);  // "other" (30 ms) goes, not "kept"
    EXPECT_NE(cache.findLastSolve("kept"), nullptr);
    EXPECT_EQ(cache.findLastSolve("other"), nullptr);
    // Each drop raises the clock: entries put later outrank one never used again, so even the
    // dearest goes once enough newer ones came and went.
    cache.putLastSolve("dearest", floats(10), 400);  // 10 ms a byte
    for (int i = 0; i < 200; ++i) cache.putLastSolve("passing" + std::to_string(i), floats(10), 60 + i);
    EXPECT_EQ(cache.findLastSolve("dearest"), nullptr);
    EXPECT_LE(cache.bytes(), 100u);
}

}  // namespace

// A session's versions (issue #9): every number stays listed; once on disk, only the current
// volume and the most recently used older one stay in memory; without a disk, all stay.
#include <gtest/gtest.h>

#include "core/volume/builtin_scenes.h"
#include "server/state/version_history.h"

using namespace volstyle;
using server::VersionHistory;

TEST(VersionHistory, StoredVersionsLeaveMemoryButTheMostRecentlyUsed) {
    const core::Volume v = core::makeBuiltinScene("sphere", 8);
    VersionHistory h;
    h.add(1);
    h.markStored(1, 100);
    for (int n = 2; n <= 6; ++n) {  // commit 2..6: each retires the one before
        h.retire(n - 1, v);
        h.add(n);
        h.markStored(n, 100);
        EXPECT_LE(h.inMemoryCount(), 1u) << "after version " << n;
    }
    EXPECT_EQ(h.numbers(), (std::set<int>{1, 2, 3, 4, 5, 6}));
    EXPECT_NE(h.inMemory(5), nullptr) << "the version just retired is the likely next revert";
    EXPECT_EQ(h.inMemory(2), nullptr);
    h.remember(2, v);  // read back for a revert
    EXPECT_NE(h.inMemory(2), nullptr);
    EXPECT_EQ(h.inMemory(5), nullptr);
    EXPECT_EQ(h.inMemoryCount(), 1u);
    EXPECT_TRUE(h.unstored().empty());
}

TEST(VersionHistory, WithoutADiskEveryVersionStaysInMemory) {
    const core::Volume v = core::makeBuiltinScene("sphere", 8);
    VersionHistory h;
    h.add(1);
    for (int n = 2; n <= 4; ++n) {
        h.retire(n - 1, v);
        h.add(n);
    }
    EXPECT_EQ(h.inMemoryCount(), 3u);
    EXPECT_EQ(h.unstored(), (std::vector<int>{1, 2, 3, 4}));
}

TEST(VersionHistory, DamagedVersionsStayListedWithTheirReason) {
    VersionHistory h;
    h.add(1);
    h.add(2);
    h.markStored(1, 10);
    h.markDamaged(1, "truncated");
    EXPECT_TRUE(h.has(1));
    EXPECT_EQ(h.damage(1).value_or(""), "truncated");
    EXPECT_FALSE(h.isStored(1));
    EXPECT_EQ(h.unstored(), (std::vector<int>{2})) << "a damaged version is not written again";
    EXPECT_EQ(h.newest(), 2);
}

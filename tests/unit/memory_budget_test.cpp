// Sessions are charged by what they hold decoded (server/service/memory_budget.h, issue #35): additions
// over the session's or the server's budget are refused naming it, and deletions release.
#include <gtest/gtest.h>

#include "protocol/error_code.h"
#include "server/service/memory_budget.h"
#include "server/state/session_store.h"

using namespace volstyle;
using namespace volstyle::server;

namespace {

constexpr size_t kFrameBytes = 16 * 16 * 16 * 3 * sizeof(float);  // one 16³ extinction grid

core::Volume frame() { return core::Volume({16, 16, 16}, Mat4{}); }

/// The message of the ApiError `f` throws (empty: none).
template <typename F>
std::string refusal(F&& f, protocol::ErrorCode code = protocol::ErrorCode::OutOfBudget) {
    try {
        f();
    } catch (const protocol::ApiError& e) {
        EXPECT_EQ(e.code(), code);
        return e.what();
    }
    return {};
}

}  // namespace

TEST(MemoryBudget, DecodedBytesCountEverythingASessionHolds) {
    Session s;
    s.volume.current = frame();
    EXPECT_EQ(decodedBytes(s), kFrameBytes);
    s.frames[3].volume = frame();
    s.frames[3].volume.ensureAlbedo();
    EXPECT_EQ(decodedBytes(s), 3 * kFrameBytes) << "a frame's albedo counts too";
    s.views.list.push_back({});
    s.views.list.back().target = core::Image(10, 10);
    EXPECT_EQ(decodedBytes(s), 3 * kFrameBytes + 10 * 10 * 4 * sizeof(float));
}

TEST(MemoryBudget, ASessionIsRefusedPastItsBudgetAndDeletionReleases) {
    MemoryBudget budget({/*perSession=*/4 * kFrameBytes, /*total=*/100 * kFrameBytes});
    Session s;
    s.volume.current = frame();
    budget.recount(s);
    for (int n = 0; n < 3; ++n) {
        EXPECT_EQ(refusal([&] { budget.check(s, kFrameBytes, 0, "frame " + std::to_string(n)); }), "") << n;
        s.frames[n].volume = frame();
        budget.recount(s);
    }
    EXPECT_EQ(budget.total(), 4 * kFrameBytes);
    const std::string why = refusal([&] { budget.check(s, kFrameBytes, 0, "frame 3"); });
    EXPECT_NE(why.find("frame 3 would bring the session's memory to"), std::string::npos) << why;
    EXPECT_NE(why.find("over its budget"), std::string::npos) << why;
    EXPECT_EQ(refusal([&] { budget.check(s, kFrameBytes, kFrameBytes, "frame 2 again"); }), "") << "a replacement frees the old one";
    s.frames.erase(0);
    budget.recount(s);
    EXPECT_EQ(refusal([&] { budget.check(s, kFrameBytes, 0, "frame 3"); }), "") << "a deleted frame made room";
    budget.forget(s);
    EXPECT_EQ(budget.total(), 0u);
}

TEST(MemoryBudget, TheServersBudgetCountsEverySession) {
    MemoryBudget budget({/*perSession=*/10 * kFrameBytes, /*total=*/5 * kFrameBytes});
    Session a, b;
    a.volume.current = frame();
    for (int n = 0; n < 3; ++n) a.frames[n].volume = frame();
    budget.recount(a);
    b.volume.current = frame();
    budget.recount(b);
    EXPECT_EQ(budget.total(), 5 * kFrameBytes);
    // The server's budget is the server's state: 503 overloaded (with Retry-After at the door).
    const std::string why = refusal([&] { budget.check(b, kFrameBytes, 0, "frame 0"); }, protocol::ErrorCode::Overloaded);
    EXPECT_NE(why.find("over the server's memory budget"), std::string::npos) << why;
    EXPECT_EQ(protocol::httpStatus(protocol::ErrorCode::Overloaded), 503);
    EXPECT_EQ(protocol::httpStatus(protocol::ErrorCode::OutOfBudget), 507);
    EXPECT_NE(refusal([&] { budget.checkNew(kFrameBytes, "a new session"); }, protocol::ErrorCode::Overloaded), "");
    budget.forget(a);
    EXPECT_EQ(refusal([&] { budget.check(b, kFrameBytes, 0, "frame 0"); }), "");
}

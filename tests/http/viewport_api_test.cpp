// The painting page's viewport as a live stream (issue #40 item 4): PUT …/viewport sets the
// camera and render options, GET …/viewport/stream sends a JPEG frame whenever the viewport moves
// or what the session shows changes (a new version, the lighting), a burst of moves renders only
// its newest, and the stream ends with the session. Each frame is checked against the PNG of
// POST …/render with the same body, to the JPEG codec's error.
#include <gtest/gtest.h>

#include <cmath>

#include "api_fixture.h"
#include "core/image/image.h"
#include "multipart_stream.h"
#include "server/state/stylizer_state.h"

using namespace volstyle;
using namespace volstyle::test;

namespace {

class ViewportApi : public Api {};

json viewportBody(double azimuth, int size = 40) {
    return {{"camera", {{"eye", {3 * std::sin(azimuth), 0.4, 3 * std::cos(azimuth)}}, {"target", {0, 0, 0}}, {"width", size}, {"height", size}}},
            {"format", "jpeg"}};
}

/// Mean and largest difference of two pictures in 8-bit sRGB levels.
std::pair<double, double> levelsApart(const core::Image& a, const core::Image& b) {
    double sum = 0, worst = 0;
    for (size_t i = 0; i < a.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = 255.0 * std::abs(core::linearToSrgb(a.rgba[4 * i + size_t(c)]) - core::linearToSrgb(b.rgba[4 * i + size_t(c)]));
            sum += d, worst = std::max(worst, d);
        }
    return {sum / double(3 * a.pixelCount()), worst};
}

}  // namespace

TEST_F(ViewportApi, TheStreamShowsTheViewportAndFollowsItsMovesAndTheSessionsEdits) {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    EXPECT_EQ(json::parse(client().Get((base + "/viewport").c_str())->body)["revision"], 0);
    expectError(client().Put((base + "/viewport").c_str(), R"({"camera": {"width": 0}})", "application/json"), 400, "invalid_argument");

    MultipartStream stream(m_port, base + "/viewport/stream");
    EXPECT_FALSE(stream.waitForJpegs(1, 1.0)) << "no frame before the page says what to show";
    auto put = client().Put((base + "/viewport").c_str(), viewportBody(0).dump(), "application/json");
    ASSERT_EQ(put->status, 200) << put->body;
    EXPECT_EQ(json::parse(put->body)["revision"], 1);
    ASSERT_TRUE(stream.waitForJpegs(1)) << "the viewport's frame comes";
    EXPECT_EQ(stream.contentType(), "multipart/x-mixed-replace; boundary=volstyle-frame");
    const StreamPart first = stream.parts()[0];
    EXPECT_EQ(first.number("X-Revision"), 1u);
    EXPECT_EQ(first.number("X-Version"), 1u);
    EXPECT_EQ(first.number("X-Width"), 40u);

    // The frame is the PNG render of the same body, to JPEG's error (quality 90).
    json pngBody = viewportBody(0);
    pngBody["format"] = "png";
    auto r = client().Post((base + "/render").c_str(), pngBody.dump(), "application/json");
    ASSERT_EQ(r->status, 200);
    const core::Image png = core::loadImageFromMemory(r->body.data(), r->body.size(), "png").image;
    const core::Image jpeg = core::loadImageFromMemory(first.body.data(), first.body.size(), "jpeg").image;
    ASSERT_EQ(jpeg.width, png.width);
    const auto [mean, worst] = levelsApart(jpeg, png);
    std::printf("[ measured ] streamed viewport JPEG (quality %d) vs the PNG render: mean %.2f, largest %.0f levels of 255\n",
                server::kLiveJpegQuality, mean, worst);
    EXPECT_LE(mean, 2.0);  // a smooth sphere: JPEG's error is well under the forest's (mean 3.2)
    EXPECT_LE(worst, 24.0);

    // An edit of the volume (a new version) streams a frame without a PUT, and so does the lighting.
    ASSERT_EQ(client().Post((base + "/refraction").c_str(), R"({"index": 1.4, "radius": 0.6})", "application/json")->status, 200);
    ASSERT_TRUE(stream.waitUntil([](const auto& parts) { return parts.back().number("X-Version") == 2; })) << "a new version is shown";
    const uint64_t shownAfterEdit = stream.parts().back().number("X-Shown");
    EXPECT_EQ(stream.parts().back().number("X-Revision"), 1u);
    const json lighting = json::parse(client().Get((base + "/lighting").c_str())->body);
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), lighting.dump(), "application/json")->status, 200);
    ASSERT_TRUE(stream.waitUntil([&](const auto& parts) { return parts.back().number("X-Shown") > shownAfterEdit; })) << "the lighting is shown";

    // A burst of moves: frames in order, none twice, the last move's frame arrives.
    uint64_t last = 0;
    for (int k = 1; k <= 6; ++k) last = json::parse(client().Put((base + "/viewport").c_str(), viewportBody(0.3 * k).dump(), "application/json")->body)["revision"];
    EXPECT_EQ(last, 7u);
    ASSERT_TRUE(stream.waitUntil([&](const auto& parts) { return parts.back().number("X-Revision") == last; }));
    const std::vector<StreamPart> parts = stream.parts();
    for (size_t i = 1; i < parts.size(); ++i) {
        const auto before = std::pair(parts[i - 1].number("X-Revision"), parts[i - 1].number("X-Shown"));
        const auto after = std::pair(parts[i].number("X-Revision"), parts[i].number("X-Shown"));
        EXPECT_LT(before, after) << "part " << i;
    }
    std::printf("[ measured ] %zu frames for %d viewport moves and 2 edits\n", stream.jpegs(), 7);

    ASSERT_EQ(client().Delete(base.c_str())->status, 204);
    stream.join();
    EXPECT_NE(stream.parts().back().body.find("\"closed\""), std::string::npos) << "the stream ends with the session";
}

// Request types parse once, at the door (issue #8): every body field and query parameter is
// validated by its protocol type with the SPEC error body's JSON Pointers.
#include <gtest/gtest.h>

#include "protocol/requests.h"

using namespace volstyle;
using json = nlohmann::json;

namespace {

/// The paths of the problems `parse` reports (empty when it succeeds).
template <typename F>
std::vector<std::string> problemPaths(F&& parse) {
    try {
        parse();
    } catch (const protocol::ValidationError& e) {
        std::vector<std::string> out;
        for (const auto& d : e.details()) out.push_back(d.path);
        return out;
    }
    return {};
}

}  // namespace

TEST(Requests, QueryNumbersAreWholeAndFinite) {
    using Q = protocol::ViewRenderQuery;
    EXPECT_DOUBLE_EQ(Q::fromQuery({{"exposure", "-1.5"}}).exposure, -1.5);
    EXPECT_DOUBLE_EQ(Q::fromQuery({{"t", "123"}}).exposure, 0.0) << "unknown parameters (cache busters) are ignored";
    for (const char* bad : {"nan", "abc", "inf", "1.5x", ""})
        EXPECT_EQ(problemPaths([&] { Q::fromQuery({{"exposure", bad}}); }), std::vector<std::string>{"?exposure"}) << bad;
    using V = protocol::VolumeQuery;
    EXPECT_EQ(V::fromQuery({{"version", "3"}}).version, 3);
    EXPECT_FALSE(V::fromQuery({}).version.has_value());
    for (const char* bad : {"0", "-2", "1e3", "4294967297", "two"})
        EXPECT_EQ(problemPaths([&] { V::fromQuery({{"version", bad}}); }), std::vector<std::string>{"?version"}) << bad;
}

TEST(Requests, IntegersDoNotWrap) {
    protocol::RequestLimits limits;
    EXPECT_EQ(problemPaths([&] { protocol::CreateSessionRequest::fromJson(json{{"resolution", 4294967360ull}}, limits); }),
              std::vector<std::string>{"/resolution"});
    EXPECT_EQ(problemPaths([&] { protocol::RevertRequest::fromJson(json{{"version", 4294967297ll}}); }),
              std::vector<std::string>{"/version"});
    EXPECT_EQ(protocol::RevertRequest::fromJson(json{{"version", 2}}).version, 2);
}

TEST(Requests, OneCameraBlockWithTheImageLimit) {
    protocol::RequestLimits limits;
    limits.maxImageSide = 64;
    json body = {{"camera", {{"eye", {0, 0, 3}}, {"target", {0, 0, 0}}, {"width", 65}, {"height", 8}}}};
    for (auto parse : {+[](const json& b, const protocol::RequestLimits& l) { protocol::RenderRequest::fromJson(b, l); },
                       +[](const json& b, const protocol::RequestLimits& l) { protocol::AddViewRequest::fromJson(b, l); }}) {
        try {
            parse(body, limits);
            ADD_FAILURE() << "a 65-pixel side passed a 64-pixel limit";
        } catch (const protocol::ApiError& e) {
            EXPECT_EQ(e.code(), protocol::ErrorCode::TooLarge) << "over a limit: 413, the limit named";
            ASSERT_EQ(e.details().size(), 1u);
            EXPECT_EQ(e.details()[0].path, "/camera/width");
            EXPECT_NE(std::string(e.what()).find("64"), std::string::npos);
        }
    }
    EXPECT_EQ(problemPaths([&] { protocol::AddViewRequest::fromJson(json::object(), limits); }), std::vector<std::string>{"/camera"});
    body["camera"]["width"] = 32;
    body["format"] = "exr";
    body["exposure"] = 1;
    auto r = protocol::RenderRequest::fromJson(body, limits);
    EXPECT_EQ(r.camera.width, 32);
    EXPECT_EQ(r.format, protocol::ImageFormat::Exr);
    body["format"] = "gif";
    body["mode"] = "pathtraced";
    EXPECT_EQ(problemPaths([&] { protocol::RenderRequest::fromJson(body, limits); }), (std::vector<std::string>{"/format", "/mode"}));
}

TEST(Requests, SessionSceneAndResolution) {
    protocol::RequestLimits limits;
    auto q = protocol::CreateSessionRequest::fromJson(json::object(), limits);
    EXPECT_EQ(q.scene, "builtin:cloud");
    EXPECT_EQ(q.builtinName(), "cloud");
    EXPECT_EQ(problemPaths([&] { protocol::CreateSessionRequest::fromJson(json{{"scene", "/etc/passwd"}, {"resolution", 4}}, limits); }),
              (std::vector<std::string>{"/scene", "/resolution"}));
}

TEST(Requests, AnExtinctionSolveWithoutMediumRadianceIsOfferedTheBackground) {
    // The hint once came from the route matching the message's words ("is required"); now the
    // parser adds it when the field is absent, whatever the message says.
    const json j = {{"unknowns", {"extinction"}}};
    const Vec3d background{0.25, 0.5, 0.75};
    for (const bool offered : {false, true}) {
        try {
            protocol::SolveRequest::fromJson(j, {}, offered ? &background : nullptr);
            FAIL() << "an extinction solve needs medium_radiance";
        } catch (const protocol::ValidationError& e) {
            ASSERT_EQ(e.details().size(), 1u);
            EXPECT_EQ(e.details()[0].path, "/medium_radiance");
            const bool hinted = e.details()[0].message.find("e.g. the background's, \"medium_radiance\": [0.25, 0.5, 0.75]") != std::string::npos;
            EXPECT_EQ(hinted, offered) << e.details()[0].message;
        }
    }
    // A wrong value is not "left out": no hint.
    try {
        protocol::SolveRequest::fromJson({{"unknowns", {"extinction"}}, {"medium_radiance", {-1, 0, 0}}}, {}, &background);
        FAIL() << "a negative L_m";
    } catch (const protocol::ValidationError& e) {
        EXPECT_EQ(e.details()[0].message.find("e.g."), std::string::npos) << e.details()[0].message;
    }
}

// Authoring the stylizer's transfer function in the scene (issue #15): a TF of layers in the scene
// resource, constraints clicked into the frame (their TF position is the pixel's AOVs and the
// pixel then shows their colour), anchors that follow an occluder as it and the camera move, and
// undo/redo of scene changes. Frames are 64×36 (the fixture's image limit is 64 a side).
#include <algorithm>
#include <cmath>
#include <set>

#include "core/stylize/tf_anchors.h"
#include "protocol/stylize_json.h"
#include "../common/image_compare.h"
#include "server/runtime/video_encoder.h"
#include "stylizer_fixture.h"

namespace volstyle::test {
namespace {

class TfAuthoringApi : public StylizerApi {
protected:
    core::Image aov(const char* name) { return frame({{"format", "exr"}, {"aov", name}}); }
    json postConstraint(const json& body) {
        auto r = client().Post((base + "/constraints").c_str(), body.dump(), "application/json");
        EXPECT_EQ(r->status, 200) << r->body;
        return json::parse(r->body);
    }
    /// The TF's part of a pixel of `styledFrame`: the frame less its physical surfaces.
    static double styledPart(const core::Image& styledFrame, const core::Image& physical, const core::Image& scattering, int x, int y, int c) {
        return double(styledFrame.pixel(x, y)[c]) - physical.pixel(x, y)[c] + scattering.pixel(x, y)[c];
    }
};

/// The pixel whose (V̄, d) is farthest from pixel `a`'s.
std::pair<int, int> farthestInTf(const core::Image& vBar, const core::Image& depth, int ax, int ay) {
    std::pair<int, int> best{ax, ay};
    double most = -1;
    for (int y = 0; y < vBar.height; ++y)
        for (int x = 0; x < vBar.width; ++x) {
            const double dv = vBar.pixel(x, y)[0] - vBar.pixel(ax, ay)[0], dd = (depth.pixel(x, y)[0] - depth.pixel(ax, ay)[0]) / 40;
            if (dv * dv + dd * dd > most) most = dv * dv + dd * dd, best = {x, y};
        }
    return best;
}

TEST_F(TfAuthoringApi, AClickedConstraintSitsAtThePixelsAovsAndGivesThePixelItsColour) {
    for (const char* mode : {"replace", "multiply"}) {
        SCOPED_TRACE(mode);
        json s = smallForest();
        s.erase("transfer_function");
        ASSERT_EQ(putScene(s)->status, 200);
        const core::Image physical = frame(), vBar = aov("average_visibility"), depth = aov("linear_depth");
        const core::Image scattering = aov("scattering");
        s["transfer_function"] = {{"mode", mode}, {"depth_range", {0, 40}}, {"layers", {{{"type", "diffusion"}}}}};
        ASSERT_EQ(putScene(s)->status, 200);
        const int ax = 20, ay = 30;
        const auto [bx, by] = farthestInTf(vBar, depth, ax, ay);
        const Vec3d red{0.9, 0.2, 0.1}, green{0.1, 0.7, 0.3};
        for (auto [x, y, colour, alpha] : {std::tuple{ax, ay, red, 1.0}, std::tuple{bx, by, green, 0.8}}) {
            const json added = postConstraint({{"x", x}, {"y", y}, {"colour", {colour.x, colour.y, colour.z}}, {"alpha", alpha}});
            EXPECT_EQ(added["layer"], 0);
            EXPECT_NEAR(added["constraint"]["v_bar"].get<double>(), vBar.pixel(x, y)[0], 1e-6);
            EXPECT_NEAR(added["constraint"]["depth"].get<double>(), std::clamp(depth.pixel(x, y)[0] / 40.0, 0.0, 1.0), 1e-6);
        }
        const core::Image styled = frame();
        for (auto [x, y, colour, alpha] : {std::tuple{ax, ay, red, 1.0}, std::tuple{bx, by, green, 0.8}})
            for (int c = 0; c < 3; ++c) {
                const double want = std::string(mode) == "replace" ? colour[c] * alpha : colour[c] * scattering.pixel(x, y)[c];
                EXPECT_NEAR(styledPart(styled, physical, scattering, x, y, c), want, 1.0 / 255) << x << "," << y << " channel " << c;
            }
        std::printf("[ measured ] %s: constraints at (%d, %d) and (%d, %d), V̄ %.3f and %.3f\n", mode, ax, ay, bx, by,
                    vBar.pixel(ax, ay)[0], vBar.pixel(bx, by)[0]);
    }
}

TEST_F(TfAuthoringApi, AnAnchoredConstraintFollowsItsOccluderAndTheCamera) {
    json s = smallForest();
    s["transfer_function"] = {{"mode", "replace"}, {"depth_range", {0, 40}},
                              {"layers", {{{"type", "diffusion"}, {"constraints", {{{"v_bar", 0.9}, {"depth", 0.9}, {"colour", {0, 0, 1}}}}}}}}};
    ASSERT_EQ(putScene(s)->status, 200);
    const json added = postConstraint({{"x", 32}, {"y", 30}, {"colour", {1, 0.5, 0}}, {"anchor", "object"}});
    ASSERT_TRUE(added["pick"]["occluder"].is_string()) << added;
    const std::string followed = added["pick"]["occluder"];
    EXPECT_EQ(added["constraint"]["anchor"]["follow"], followed);

    // Move the camera and the followed occluder; the anchored point's new pixel shows the colour.
    s = scene();
    s["camera"]["eye"][0] = s["camera"]["eye"][0].get<double>() + 1.5;
    for (auto& o : s["occluders"])
        if (o["name"] == followed) o["transform"][13] = o["transform"][13].get<double>() + 0.5;  // up by 0.5 (column-major ty)
    ASSERT_EQ(putScene(s)->status, 200) << s;
    const core::StylizerScene moved = protocol::stylizerSceneFromJson(s, "", protocol::SceneSource::Api).scene;
    core::TfAnchor anchor{Vec3d(added["constraint"]["anchor"]["position"][0], added["constraint"]["anchor"]["position"][1],
                                added["constraint"]["anchor"]["position"][2]),
                          followed};
    const auto pixel = moved.camera.project(core::anchorWorldPosition(moved, anchor));
    ASSERT_TRUE(pixel.has_value());
    json bare = s;
    bare.erase("transfer_function");
    ASSERT_EQ(putScene(bare)->status, 200);
    const core::Image physical = frame(), scattering = aov("scattering");
    ASSERT_EQ(client().Post((base + "/undo").c_str(), "", "application/json")->status, 200);
    const core::Image styled = frame();
    const double want[3] = {1, 0.5, 0};
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(styledPart(styled, physical, scattering, pixel->x, pixel->y, c), want[c], 1.0 / 255)
            << "pixel " << pixel->x << "," << pixel->y << " channel " << c;
    std::printf("[ measured ] the anchor on '%s' moved from (32, 30) to (%d, %d)\n", followed.c_str(), pixel->x, pixel->y);
}

TEST_F(TfAuthoringApi, SceneChangesUndoAndRedo) {
    expectError(client().Post((base + "/undo").c_str(), "", "application/json"), 409, "busy");
    json s = smallForest();
    ASSERT_EQ(putScene(s)->status, 200);
    s["transfer_function"] = {{"layers", {{{"type", "solid"}, {"colour", {0.5, 0.5, 0.5}}}}}, {"size", {16, 8}}};
    auto put = putScene(s);
    ASSERT_EQ(put->status, 200) << put->body;
    EXPECT_EQ(scene()["transfer_function"]["size"], json({16, 8}));
    auto r = client().Post((base + "/undo").c_str(), "", "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_FALSE(json::parse(r->body).contains("transfer_function"));
    r = client().Post((base + "/redo").c_str(), "", "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(json::parse(r->body)["transfer_function"]["layers"][0]["type"], "solid");
    expectError(client().Post((base + "/redo").c_str(), "", "application/json"), 409, "busy");
    // A change of time alone is no step: undo goes past it to the scene before the TF.
    s["time"] = 3;
    ASSERT_EQ(putScene(s)->status, 200);
    r = client().Post((base + "/undo").c_str(), "", "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_FALSE(json::parse(r->body).contains("transfer_function"));
    ASSERT_EQ(client().Post((base + "/redo").c_str(), "", "application/json")->status, 200);

    // Bad layers name their field and change nothing.
    json bad = s;
    bad["transfer_function"]["layers"][0]["colour"] = {2, 0, 0};
    bad["transfer_function"]["layers"].push_back({{"type", "gradient"}});
    json e = expectError(putScene(bad), 400, "invalid_argument");
    std::set<std::string> fields;
    for (const auto& d : e["error"]["details"]) fields.insert(d["path"].get<std::string>());
    EXPECT_TRUE(fields.count("/transfer_function/layers/0/colour")) << e;
    EXPECT_TRUE(fields.count("/transfer_function/layers/1/from")) << e;
    json noImage = s;
    noImage["transfer_function"]["layers"] = {{{"type", "image"}}};
    e = expectError(putScene(noImage), 400, "invalid_argument");
    EXPECT_EQ(e["error"]["details"][0]["path"], "/transfer_function/layers/0") << e;
    EXPECT_EQ(scene()["transfer_function"]["layers"][0]["type"], "solid");
}

TEST_F(TfAuthoringApi, ASequenceJobRendersTheCameraPathWithProgressAndAVideo) {
    json s = smallForest();
    s.erase("transfer_function");
    json later = s["camera"];
    later["eye"][0] = later["eye"][0].get<double>() + 1;
    auto solid = [](double r, double g, double b) {
        return json{{"mode", "replace"}, {"size", {8, 8}}, {"layers", {{{"type", "solid"}, {"colour", {r, g, b}}}}}};
    };
    s["keyframes"] = {{{"time", 0}, {"camera", s["camera"]}, {"transfer_function", solid(0.2, 0.4, 0.6)}},
                      {{"time", 1}, {"camera", later}, {"transfer_function", solid(0.8, 0.2, 0)}}};
    auto put = putScene(s);
    ASSERT_EQ(put->status, 200) << put->body;
    EXPECT_EQ(scene()["keyframes"].size(), 2u);
    // On a path whose keys carry TFs a clicked constraint goes into the nearest key's (time 0: key 0).
    const json added = postConstraint({{"x", 20}, {"y", 20}, {"colour", {0, 1, 0}}});
    EXPECT_EQ(added["key"], 0) << added;
    EXPECT_EQ(scene()["keyframes"][0]["transfer_function"]["layers"].size(), 2u);
    const bool video = !server::findFfmpeg().empty();
    auto r = client().Post((base + "/sequence").c_str(), json{{"fps", 4}, {"video", video}}.dump(), "application/json");
    ASSERT_EQ(r->status, 202) << r->body;
    const std::string job = json::parse(r->body)["job"];
    const auto events = readEvents(client(), "/api/v1/jobs/" + job + "/events");
    EXPECT_EQ(std::count(events.begin(), events.end(), "progress"), 5) << "a progress event per frame";
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back(), "done");
    const json result = json::parse(client().Get(("/api/v1/jobs/" + job).c_str())->body)["result"];
    ASSERT_EQ(result["frames"], 5) << result;
    auto frame = client().Get(result["frame_urls"][4].get<std::string>().c_str());
    ASSERT_EQ(frame->status, 200);
    const core::Image last = core::loadImageFromMemory(frame->body.data(), frame->body.size(), "frame").image;
    EXPECT_EQ(last.width, 64);
    EXPECT_EQ(last.height, 36);
    expectError(client().Get(("/api/v1/jobs/" + job + "/frames/5.png").c_str()), 404, "not_found");
    if (video) {
        auto mp4 = client().Get(result["video_url"].get<std::string>().c_str());
        ASSERT_EQ(mp4->status, 200);
        EXPECT_EQ(mp4->body.substr(4, 4), "ftyp") << "an MP4";
    }
    std::printf("[ measured ] 5 frames of 64x36 in %.0f ms%s\n", result["render_ms"].get<double>(), video ? ", and a video" : "");

    // Without key frames a sequence needs its end; bad fps names its field.
    s.erase("keyframes");
    ASSERT_EQ(putScene(s)->status, 200);
    json e = expectError(client().Post((base + "/sequence").c_str(), "{}", "application/json"), 400, "invalid_argument");
    EXPECT_EQ(e["error"]["details"][0]["path"], "/end") << e;
    e = expectError(client().Post((base + "/sequence").c_str(), R"({"fps": 0, "end": 1})", "application/json"), 400, "invalid_argument");
    EXPECT_EQ(e["error"]["details"][0]["path"], "/fps") << e;
}

TEST_F(TfAuthoringApi, TheSessionVolumeIsAHeterogeneousMedium) {
    json s = smallForest();
    s.erase("transfer_function");
    ASSERT_EQ(putScene(s)->status, 200);
    const core::Image homogeneous = frame();
    s["volume"] = {{"extinction_scale", 0.5}};
    auto r = putScene(s);
    ASSERT_EQ(r->status, 200) << r->body;
    const json back = json::parse(r->body)["volume"];
    EXPECT_EQ(back["source"], "session");
    EXPECT_EQ(back["box"].size(), 2u) << "the box defaults to the session volume's bounds: " << back;
    const core::Image withVolume = frame();
    EXPECT_GT(test::maxAbsDifference(homogeneous, withVolume), 1e-3) << "the medium changed";
    for (float v : withVolume.rgba) ASSERT_TRUE(std::isfinite(v));
    json bad = s;
    bad["volume"]["source"] = "cloud.vdb";
    bad["volume"]["steps"] = 0;
    json e = expectError(putScene(bad), 400, "invalid_argument");
    std::set<std::string> fields;
    for (const auto& d : e["error"]["details"]) fields.insert(d["path"].get<std::string>());
    EXPECT_TRUE(fields.count("/volume/source") && fields.count("/volume/steps")) << e;
}

}  // namespace
}  // namespace volstyle::test

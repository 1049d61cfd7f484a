// A session's environment map, its views' background plates and the translucent render mode over
// HTTP (issues #13, #14; SPEC §1, §8, §9): upload, refusal of bad
// maps naming the problem, the lighting naming "session", renders that use them, downloads, removal,
// both surviving a restart on the data directory; translucent renders and their refusals.
#include <filesystem>
#include <set>

#include "api_fixture.h"

using namespace volstyle;
using namespace volstyle::test;

namespace {

std::string exrOf(const core::Image& img) { return core::encodeImage(img, "exr"); }

/// A lat-long map: red rising to the east, green to the north pole, blue constant.
core::Image skyMap(int width, float scale = 1) {
    core::Image map(width, width / 2);
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x) {
            float* p = map.pixel(x, y);
            p[0] = scale * (0.2f + float(x) / float(map.width));
            p[1] = scale * (1.2f - float(y) / float(map.height));
            p[2] = scale * 0.5f, p[3] = 1;
        }
    return map;
}

core::Image decode(const httplib::Result& r) {
    EXPECT_EQ(r->status, 200) << r->body;
    return core::loadImageFromMemory(r->body.data(), r->body.size(), "answer").image;
}

class EnvironmentApi : public PersistentApi {};

}  // namespace

TEST_F(EnvironmentApi, AnUploadedMapLightsAndBacksTheSessionAndSurvivesARestart) {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    const json lighting = {{"sun", {{"direction", {0, 1, 0}}, {"irradiance", {1, 1, 1}}}},
                           {"background", {{"color", {0, 0, 0}}, {"environment", "session"}}},
                           {"environment", {{"lobes", 16}, {"map", "session"}, {"light_volume_resolution", 8}}}};
    // Named before it is uploaded: 400 naming both fields, the lighting unchanged.
    json e = expectError(client().Put((base + "/lighting").c_str(), lighting.dump(), "application/json"), 400, "invalid_argument");
    ASSERT_EQ(e["error"]["details"].size(), 2u);
    EXPECT_EQ(e["error"]["details"][0]["path"], "/background/environment");
    EXPECT_EQ(e["error"]["details"][1]["path"], "/environment/map");
    // A path is never read on the server.
    json path = {{"background", {{"environment", "/etc/passwd"}}}};
    e = expectError(client().Put((base + "/lighting").c_str(), path.dump(), "application/json"), 400, "invalid_argument");
    EXPECT_NE(e["error"]["message"].get<std::string>().find("session"), std::string::npos);

    // Bad maps: not 2:1, negative, not an image. Each names the problem; nothing is stored.
    e = expectError(client().Put((base + "/environment").c_str(), exrOf(core::Image(16, 16)), "image/x-exr"), 400, "invalid_argument");
    EXPECT_NE(e["error"]["message"].get<std::string>().find("16x16"), std::string::npos) << e.dump();
    core::Image negative = skyMap(32);
    negative.pixel(3, 4)[1] = -1;
    e = expectError(client().Put((base + "/environment").c_str(), exrOf(negative), "image/x-exr"), 400, "invalid_argument");
    EXPECT_NE(e["error"]["message"].get<std::string>().find("negative"), std::string::npos) << e.dump();
    expectError(client().Put((base + "/environment").c_str(), "not an image", "image/x-exr"), 422, "unsupported_media");
    expectError(client().Get((base + "/environment.exr").c_str()), 404, "not_found");
    EXPECT_FALSE(json::parse(client().Get(base.c_str())->body).contains("environment_map"));

    // A camera looking at nothing but the background, before and after (PNG two stops down, so
    // nothing clips: an EXR answer's main layer is the medium alone, docs/FORMATS.md).
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), R"({"background": [0, 0, 0]})", "application/json")->status, 200);
    const json camera = {{"camera", {{"eye", {0, 0, 3}}, {"target", {0, 0, 6}}, {"width", 8}, {"height", 8}}}, {"exposure", -2}};
    auto render = [&] { return decode(client().Post((base + "/render").c_str(), camera.dump(), "application/json")); };
    EXPECT_EQ(render().pixel(4, 4)[0], 0.0f);  // black background

    auto r = client().Put((base + "/environment").c_str(), exrOf(skyMap(32)), "image/x-exr");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(json::parse(r->body), (json{{"width", 32}, {"height", 16}, {"used", false}}));
    r = client().Put((base + "/lighting").c_str(), lighting.dump(), "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    json answer = json::parse(r->body);
    EXPECT_EQ(answer["background"]["environment"], "session");
    EXPECT_EQ(answer["environment"]["map"], "session");
    ASSERT_EQ(answer["environment"]["radiance"].size(), 16u);  // the map's projection, for reading
    EXPECT_EQ(json::parse(client().Get(base.c_str())->body)["environment_map"], (json{{"width", 32}, {"height", 16}, {"used", true}}));

    const core::Image sky = render();
    EXPECT_GT(sky.pixel(4, 4)[1], 0.1f);  // the map behind
    // The sphere lit by the map's lobes on top of the sun: brighter than under the sun alone.
    const json sphere = {{"camera", {{"eye", {0, 0, 3}}, {"target", {0, 0, 0}}, {"width", 8}, {"height", 8}}}, {"exposure", -2}};
    const float litByMap = decode(client().Post((base + "/render").c_str(), sphere.dump(), "application/json")).pixel(4, 4)[2];

    // Busy while named; a new upload replaces what the lighting names.
    expectError(client().Delete((base + "/environment").c_str()), 409, "busy");
    r = client().Put((base + "/environment").c_str(), exrOf(skyMap(32, 2)), "image/x-exr");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_TRUE(json::parse(r->body)["used"].get<bool>());
    const core::Image brighter = render();
    EXPECT_NEAR(brighter.pixel(4, 4)[1], 2 * sky.pixel(4, 4)[1], 0.03 * sky.pixel(4, 4)[1]);  // 8-bit sRGB
    const core::Image stored = decode(client().Get((base + "/environment.exr").c_str()));
    ASSERT_EQ(stored.width, 32);
    EXPECT_NEAR(stored.pixel(5, 6)[0], skyMap(32, 2).pixel(5, 6)[0], 1e-3);  // EXR answers are half float
    EXPECT_EQ(client().Get((base + "/environment.png").c_str())->status, 200);

    // A restart brings back the map and the lighting that names it: the same pixels.
    restart();
    answer = json::parse(client().Get((base + "/lighting").c_str())->body);
    EXPECT_EQ(answer["background"]["environment"], "session");
    EXPECT_EQ(answer["environment"]["map"], "session");
    EXPECT_EQ(render().pixel(4, 4)[1], brighter.pixel(4, 4)[1]);
    const float litAfter = decode(client().Post((base + "/render").c_str(), sphere.dump(), "application/json")).pixel(4, 4)[2];
    EXPECT_GT(litAfter, litByMap);  // twice the map: more light on the sphere

    // Unnamed, it can go.
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), R"({"background": [0, 0, 0]})", "application/json")->status, 200);
    EXPECT_EQ(client().Delete((base + "/environment").c_str())->status, 204);
    EXPECT_FALSE(json::parse(client().Get(base.c_str())->body).contains("environment_map"));
    expectError(client().Get((base + "/environment.exr").c_str()), 404, "not_found");
}

TEST_F(EnvironmentApi, AViewsBackgroundPlateIsWhatItsRendersShowBehindTheVolume) {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), R"({"background": [0, 0, 0]})", "application/json")->status, 200);
    auto r = client().Post((base + "/views").c_str(),
                           json{{"camera", {{"eye", {0, 0, 3}}, {"target", {0, 0, 0}}, {"width", 20}, {"height", 16}}}}.dump(), "application/json");
    ASSERT_EQ(r->status, 201);
    const std::string view = base + "/views/" + json::parse(r->body)["id"].get<std::string>();
    EXPECT_FALSE(json::parse(r->body)["has_background"].get<bool>());

    core::Image plate(20, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 20; ++x) {
            float* p = plate.pixel(x, y);
            p[0] = 0.05f * float(x), p[1] = 0.05f * float(y), p[2] = 0.3f, p[3] = 1;
        }
    json e = expectError(client().Put((view + "/background").c_str(), exrOf(core::Image(16, 16)), "image/x-exr"), 400, "invalid_argument");
    EXPECT_NE(e["error"]["message"].get<std::string>().find("16x16"), std::string::npos);
    expectError(client().Get((view + "/background.exr").c_str()), 404, "not_found");
    r = client().Put((view + "/background").c_str(), exrOf(plate), "image/x-exr");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_TRUE(json::parse(r->body)["has_background"].get<bool>());

    // Where the sphere does not cover the pixel, the render is the plate's pixel (8-bit sRGB).
    auto check = [&] {
        const core::Image render = decode(client().Get((view + "/render.png").c_str()));
        const core::Image stored = decode(client().Get((view + "/background.exr").c_str()));
        int clear = 0;
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 20; ++x)
                if (x < 3 || x > 16) {  // the sphere covers the middle of the frame only
                    ++clear;
                    for (int c = 0; c < 3; ++c) EXPECT_NEAR(render.pixel(x, y)[c], plate.pixel(x, y)[c], 0.01) << x << "," << y;
                }
        EXPECT_GT(clear, 20);
        EXPECT_NEAR(stored.pixel(7, 9)[0], plate.pixel(7, 9)[0], 2e-3);
    };
    check();
    restart();
    EXPECT_TRUE(json::parse(client().Get(view.c_str())->body)["has_background"].get<bool>());
    check();

    r = client().Delete((view + "/background").c_str());
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_FALSE(json::parse(r->body)["has_background"].get<bool>());
    EXPECT_EQ(decode(client().Get((view + "/render.png").c_str())).pixel(0, 0)[2], 0.0f);
    expectError(client().Delete((view + "/background").c_str()), 404, "not_found");
}

TEST_F(EnvironmentApi, ALightsSolveCanSolveTheBackgroundToo) {
    // Targets rendered with the lobes as the background; from black lobes, "lights":
    // {"background": true} solves the sky behind the sphere with its lighting, and the session's
    // lighting shows the lobes as its background afterwards.
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    json radiance = json::array(), black = json::array();
    for (int i = 0; i < 8; ++i) radiance.push_back({0.2 + 0.1 * i, 0.5, 1.0 - 0.1 * i}), black.push_back({0, 0, 0});
    const json truth = {{"background", {{"color", {0, 0, 0}}, {"environment", "lobes"}}},
                        {"environment", {{"lobes", 8}, {"radiance", radiance}, {"light_volume_resolution", 8}}}};
    auto r = client().Put((base + "/lighting").c_str(), truth.dump(), "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(json::parse(r->body)["background"]["environment"], "lobes");
    for (json eye : {json{0, 0.3, 3}, json{3, 0.5, 0.5}}) {
        r = client().Post((base + "/views").c_str(), json{{"camera", {{"eye", eye}, {"target", {0, 0, 0}}, {"fov_y_deg", 60}, {"width", 16}, {"height", 16}}}}.dump(), "application/json");
        ASSERT_EQ(r->status, 201) << r->body;
        const std::string vid = json::parse(r->body)["id"];
        r = client().Post((base + "/render").c_str(), json{{"camera", {{"eye", eye}, {"target", {0, 0, 0}}, {"fov_y_deg", 60}, {"width", 16}, {"height", 16}}}, {"format", "png"}}.dump(), "application/json");
        ASSERT_EQ(client().Put((base + "/views/" + vid + "/target").c_str(), r->body, "image/png")->status, 200);
    }
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), json{{"background", {0, 0, 0}}, {"environment", {{"lobes", 8}, {"radiance", black}, {"light_volume_resolution", 8}}}}.dump(), "application/json")->status, 200);
    const json result = solveToEnd(client(), base, R"({"unknowns": ["lights"], "lights": {"background": true}, "max_iterations": 30, "regularization": {"laplacian": 0}})")["result"];
    const auto [before, after] = meanRms(result["report"]);
    std::cout << "[ measured ] lights and background over HTTP: RMS " << before << " -> " << after << "\n";
    EXPECT_LT(after, 0.05 * before);  // 8-bit targets
    const json lighting = json::parse(client().Get((base + "/lighting").c_str())->body);
    EXPECT_EQ(lighting["background"]["environment"], "lobes");
    EXPECT_EQ(result["lighting"]["background"]["environment"], "lobes");
}

TEST_F(EnvironmentApi, TranslucentRendersAndRefusesBadParameters) {
    // SPEC §9 over the API: "mode": "translucent" answers a picture (PNG, or EXR with the medium
    // and the picture as a layer); bad parameters answer 400 naming each field.
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    const json camera = {{"eye", {0, 0.3, 3}}, {"target", {0, 0, 0}}, {"width", 24}, {"height", 24}};
    auto r = client().Post((base + "/render").c_str(),
                           json{{"camera", camera}, {"mode", "translucent"}, {"translucent", {{"slice_spacing", 1.0}, {"indirect", {{"blur_angle_deg", 20}}}}}}.dump(),
                           "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    const core::Image png = decode(r);
    EXPECT_EQ(png.width, 24);
    EXPECT_GT(png.pixel(12, 12)[0], 0.05f);  // the sphere, lit
    r = client().Post((base + "/render").c_str(), json{{"camera", camera}, {"mode", "translucent"}, {"format", "exr"}}.dump(), "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_GT(decode(r).pixel(12, 12)[3], 0.5f);  // the medium's alpha

    json e = expectError(client().Post((base + "/render").c_str(),
                                       json{{"camera", camera}, {"mode", "translucent"},
                                            {"translucent", {{"slice_spacing", -1}, {"indirect", {{"blur_angle_deg", 95}, {"transport_color", {2, 0.5, 0.5}}}}, {"surface_shading", "x"}}}}.dump(),
                                       "application/json"),
                         400, "invalid_argument");
    std::set<std::string> paths;
    for (const auto& d : e["error"]["details"]) paths.insert(d["path"].get<std::string>());
    EXPECT_EQ(paths, (std::set<std::string>{"/translucent/slice_spacing", "/translucent/indirect/blur_angle_deg",
                                            "/translucent/indirect/transport_color", "/translucent/surface_shading"}));
    e = expectError(client().Post((base + "/render").c_str(), json{{"camera", camera}, {"translucent", json::object()}}.dump(), "application/json"),
                    400, "invalid_argument");
    EXPECT_EQ(e["error"]["details"][0]["path"], "/translucent");
    expectError(client().Post((base + "/render").c_str(), json{{"camera", camera}, {"mode", "path_traced"}}.dump(), "application/json"), 400,
                "invalid_argument");
}

TEST_F(EnvironmentApi, APerturbationBakesIntoANewVersion) {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    json e = expectError(client().Post((base + "/perturb").c_str(), R"({"amplitude": -1, "octaves": 0})", "application/json"), 400, "invalid_argument");
    std::set<std::string> paths;
    for (const auto& d : e["error"]["details"]) paths.insert(d["path"].get<std::string>());
    EXPECT_EQ(paths, (std::set<std::string>{"/amplitude", "/octaves"}));
    e = expectError(client().Post((base + "/perturb").c_str(), "{}", "application/json"), 400, "invalid_argument");  // nothing to bake
    EXPECT_EQ(e["error"]["details"][0]["path"], "/amplitude");
    auto r = client().Post((base + "/perturb").c_str(), R"({"amplitude": 1.5, "frequency": 6, "seed": 3})", "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(json::parse(r->body)["volume"]["version"], 2);
    // The old content is still there to revert to.
    EXPECT_EQ(client().Post((base + "/revert").c_str(), R"({"version": 1})", "application/json")->status, 200);
}

#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "protocol/render_json.h"
#include "protocol/solve_json.h"

using namespace volstyle;
using json = nlohmann::json;

namespace {

std::vector<protocol::FieldError> errorsOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const protocol::ValidationError& e) {
        return e.details();
    }
    return {};
}

}  // namespace

TEST(CameraJson, ParsesAndRoundTrips) {
    json j = {{"eye", {1, 2, 3}}, {"target", {0, 0, 0}}, {"fov_y_deg", 30}, {"width", 64}, {"height", 32}};
    core::Camera c = protocol::cameraFromJson(j);
    EXPECT_EQ(c.eye, Vec3d(1, 2, 3));
    EXPECT_EQ(c.width, 64);
    EXPECT_EQ(protocol::cameraFromJson(protocol::cameraToJson(c)).fovYDeg, 30);
}

TEST(CameraJson, ReportsEveryBadFieldWithItsPointer) {
    json j = {{"eye", {1, 2}}, {"target", {0, 0, 0}}, {"fov_y_deg", "wide"}, {"width", 1.5}, {"zoom", 2}};
    auto errors = errorsOf([&] { protocol::cameraFromJson(j, "/camera"); });
    std::set<std::string> paths;
    for (const auto& e : errors) paths.insert(e.path);
    EXPECT_EQ(paths, (std::set<std::string>{"/camera/eye", "/camera/fov_y_deg", "/camera/width", "/camera/zoom"}));
}

TEST(CameraJson, RangeProblemsUseJsonPointers) {
    json j = {{"eye", {0, 0, 0}}, {"target", {0, 0, 0}}, {"fov_y_deg", 200}};
    auto errors = errorsOf([&] { protocol::cameraFromJson(j, "/camera"); });
    ASSERT_EQ(errors.size(), 2u);
    EXPECT_EQ(errors[0].path, "/camera/target");
    EXPECT_EQ(errors[1].path, "/camera/fov_y_deg");
    EXPECT_EQ(errors[1].message, "must be in (0, 180)");
}

TEST(CameraJson, UnknownFieldHasItsOwnCode) {
    try {
        protocol::cameraFromJson({{"eye", {0, 0, 1}}, {"target", {0, 0, 0}}, {"lens", 35}});
        FAIL();
    } catch (const protocol::ValidationError& e) {
        EXPECT_STREQ(e.code(), "unknown_field");
    }
}

TEST(LightingJson, SunPhaseAndBackground) {
    json j = {{"sun", {{"direction", {0, 1, 0}}, {"irradiance", {2, 2, 2}}}},
              {"background", {0.1, 0.2, 0.3}},
              {"phase", {{"type", "henyey_greenstein"}, {"g", 0.4}}}};
    auto r = protocol::lightingFromJson(j);
    ASSERT_EQ(r.lighting.lights.size(), 1u);
    EXPECT_EQ(r.lighting.phase.type, core::PhaseType::HenyeyGreenstein);
    EXPECT_EQ(r.lighting.background.color, Vec3d(0.1, 0.2, 0.3));
    EXPECT_EQ(protocol::lightingFromJson(protocol::lightingToJson(r.lighting)).lighting.phase.g, 0.4);
}

TEST(LightingJson, RejectsBadValuesAndServerPaths) {
    auto errors = errorsOf([] {
        protocol::lightingFromJson({{"phase", {{"type", "rayleigh"}}}, {"sun", {{"direction", {0, 1, 0}}}}});
    });
    ASSERT_EQ(errors.size(), 2u);
    EXPECT_EQ(errors[0].path, "/sun/irradiance");
    EXPECT_EQ(errors[1].path, "/phase/type");
    errors = errorsOf([] { protocol::lightingFromJson({{"background", {{"environment", "/etc/passwd"}}}}); });
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_EQ(errors[0].path, "/background/environment");
    EXPECT_EQ(protocol::lightingFromJson({{"background", {{"environment", "sky.exr"}}}}, "", true).environmentPath, "sky.exr");
}

TEST(LightingJson, DefaultLightingMatchesTheExampleFile) {
    std::ifstream f(std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/lighting.json");
    core::Lighting fromFile = protocol::lightingFromJson(nlohmann::json::parse(f)).lighting;
    core::Lighting builtIn = core::defaultLighting();
    ASSERT_EQ(fromFile.lights.size(), builtIn.lights.size());
    for (size_t i = 0; i < builtIn.lights.size(); ++i) {
        EXPECT_EQ(fromFile.lights[i].direction, builtIn.lights[i].direction);
        EXPECT_EQ(fromFile.lights[i].irradiance, builtIn.lights[i].irradiance);
    }
    EXPECT_EQ(fromFile.background.color, builtIn.background.color);
    EXPECT_EQ(fromFile.phase.g, builtIn.phase.g);
    std::ifstream c(std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/camera.json");
    core::Camera cam = protocol::cameraFromJson(nlohmann::json::parse(c));
    EXPECT_EQ(cam.eye, core::defaultCamera().eye);
    EXPECT_EQ(cam.fovYDeg, core::defaultCamera().fovYDeg);
}

TEST(SolveJson, ParsesEveryFieldAndPerUnknownWeights) {
    auto o = protocol::solveOptionsFromJson(nlohmann::json::parse(R"({
        "unknowns": ["albedo", "emission"], "basis": "box", "max_iterations": 12, "tolerance": 1e-5,
        "step": 1.0, "traversal": "exact", "hull": "none", "resolution": {"emission": [8, 8, 8], "albedo": [8, 8, 8]},
        "regularization": {"laplacian": 0.01, "albedo": {"toward_one": 0.5}}, "views": ["v2"],
        "coarse_iterations": 3})"));
    EXPECT_EQ(o.unknown, core::Unknown::EmissionAlbedo);
    EXPECT_EQ(o.coarseIterations, 3);
    EXPECT_EQ(o.basis, core::BasisType::Box);
    EXPECT_EQ(o.maxIterations, 12);
    EXPECT_FALSE(o.useHull);
    EXPECT_TRUE(o.exactTraversal);
    EXPECT_EQ(o.resolution->x, 8);
    EXPECT_EQ(o.regularizationFor(core::Unknown::Emission).towardOne, 0.0);
    EXPECT_EQ(o.regularizationFor(core::Unknown::Albedo).towardOne, 0.5);
    EXPECT_EQ(o.regularizationFor(core::Unknown::Albedo).laplacian, 0.01);  // inherited
    EXPECT_EQ(o.views, std::vector<std::string>{"v2"});
    auto back = protocol::solveOptionsFromJson(protocol::solveOptionsToJson(o));
    EXPECT_EQ(back.regularizationFor(core::Unknown::Albedo).towardOne, 0.5);
}

TEST(SolveJson, ReportsBadFields) {
    try {
        protocol::solveOptionsFromJson(nlohmann::json::parse(R"({"unknowns": ["colour"], "hull": "maybe", "tolerance": "low",
            "resolution": {"emission": [8, 8]}, "regularization": {"albedo": {"smooth": 1}}, "extra": 1})"));
        FAIL();
    } catch (const protocol::ValidationError& e) {
        std::set<std::string> paths;
        for (const auto& d : e.details()) paths.insert(d.path);
        EXPECT_EQ(paths, (std::set<std::string>{"/unknowns", "/hull", "/tolerance", "/resolution/emission",
                                                "/regularization/albedo/smooth", "/extra"}));
    }
}

TEST(Schema, EmbeddedSchemaParsesAndDefinesEveryBody) {
    auto schema = nlohmann::json::parse(protocol::kSchemaV1);
    for (const char* d : {"error", "health", "scenes", "session", "view", "lighting", "job", "job_accepted", "solve_options"})
        EXPECT_TRUE(schema["definitions"].contains(d)) << d;
}

TEST(LightingJson, EveryProblemAtOnceUnderTheFieldItCameFrom) {
    // A bad sun direction (a value check) and a malformed background (a type error) together;
    // the value check names /sun, not the internal /lights/0.
    auto errors = errorsOf([] {
        protocol::lightingFromJson({{"sun", {{"direction", {0, 0, 0}}, {"irradiance", {1, 1, -1}}}},
                                    {"lights", json::array({{{"direction", {0, 1, 0}}, {"irradiance", {1, 1, 1}}},
                                                            {{"direction", {0, 0, 0}}, {"irradiance", {1, 1, 1}}}})},
                                    {"background", {0.3, "x", 1}}});
    });
    std::set<std::string> paths;
    for (const auto& e : errors) paths.insert(e.path);
    EXPECT_EQ(paths, (std::set<std::string>{"/sun/direction", "/sun/irradiance", "/lights/1/direction", "/background/1"}));
    // A camera whose eye failed to read is not also told its target equals the default eye.
    errors = errorsOf([] { protocol::cameraFromJson({{"eye", "here"}, {"target", {0, 0, 3}}, {"fov_y_deg", 200}}); });
    paths.clear();
    for (const auto& e : errors) paths.insert(e.path);
    EXPECT_EQ(paths, (std::set<std::string>{"/eye", "/fov_y_deg"}));
}

TEST(LightingJson, EnvironmentLobesRoundTrip) {
    json radiance = json::array();
    for (int i = 0; i < 4; ++i) radiance.push_back({0.1 * i, 0.2, 0.3});
    json j = {{"environment", {{"lobes", 4}, {"domain", "upper_hemisphere"}, {"radiance", radiance}, {"strength", 2.0},
                               {"light_volume_resolution", 32}}}};
    const core::Lighting l = protocol::lightingFromJson(j).lighting;
    EXPECT_EQ(l.environment.lobes, 4);
    EXPECT_EQ(l.environment.domain, core::LobeDomain::UpperHemisphere);
    EXPECT_EQ(l.environment.lightVolumeResolution, 32);
    ASSERT_EQ(l.environment.radiance.size(), 4u);
    EXPECT_EQ(l.environment.radiance[3], Vec3d(0.1 * 3, 0.2, 0.3));
    const core::Lighting back = protocol::lightingFromJson(protocol::lightingToJson(l)).lighting;
    EXPECT_EQ(back.environment.radiance, l.environment.radiance);
    EXPECT_EQ(back.environment.strength, 2.0);
    EXPECT_FALSE(protocol::lightingToJson(core::Lighting{}).contains("environment"));
}

TEST(LightingJson, EnvironmentProblemsNameTheirField) {
    auto paths = [](const json& env) {
        std::set<std::string> out;
        for (const auto& e : errorsOf([&] { protocol::lightingFromJson({{"environment", env}}); })) out.insert(e.path);
        return out;
    };
    EXPECT_EQ(paths({{"lobes", 300}, {"radiance", json::array()}}), (std::set<std::string>{"/environment/lobes"}));
    EXPECT_EQ(paths({{"lobes", 0}, {"radiance", json::array()}}), (std::set<std::string>{"/environment/lobes"}));
    EXPECT_EQ(paths({{"lobes", 2}, {"radiance", {{1, 1, 1}}}}), (std::set<std::string>{"/environment/radiance"}));
    EXPECT_EQ(paths({{"lobes", 1}, {"radiance", {{1, -1, 1}}}}), (std::set<std::string>{"/environment/radiance/0"}));
    EXPECT_EQ(paths({{"lobes", 1}, {"map", "sky.exr"}}), (std::set<std::string>{"/environment/map"}));  // no server paths
    EXPECT_EQ(paths({{"lobes", 1}, {"radiance", {{1, 1, 1}}}, {"domain", "disc"}}), (std::set<std::string>{"/environment/domain"}));
    EXPECT_EQ(paths({{"lobes", 1}, {"radiance", {{1, 1, 1}}}, {"colour", 1}}), (std::set<std::string>{"/environment/colour"}));
    EXPECT_EQ(paths({{"lobes", 1}, {"radiance", {{1e10, 1, 1}}}, {"strength", 1e25}}), (std::set<std::string>{"/environment/strength"}));
    EXPECT_EQ(paths({{"lobes", 1}, {"radiance", {{1, 1, 1}}}, {"light_volume_resolution", 1}}),
              (std::set<std::string>{"/environment/light_volume_resolution"}));
}

TEST(LightingJson, SessionMapIsNamedResolvedAndWrittenBack) {
    // Over the API, "session" names the session's uploaded map (and nothing else is a map).
    const json j = {{"background", {{"color", {0.1, 0.2, 0.3}}, {"environment", "session"}}},
                    {"environment", {{"lobes", 4}, {"map", "session"}}}};
    const protocol::LightingRequest request = protocol::lightingFromJson(j);
    EXPECT_TRUE(request.backgroundUsesSessionMap);
    EXPECT_TRUE(request.environmentUsesSessionMap);
    std::set<std::string> missing;
    for (const auto& e : errorsOf([&] { request.resolve(nullptr); })) missing.insert(e.path);
    EXPECT_EQ(missing, (std::set<std::string>{"/background/environment", "/environment/map"}));

    auto map = std::make_shared<core::Image>(8, 4);
    for (float& x : map->rgba) x = 0.5f;
    const core::Lighting l = request.resolve(map);
    EXPECT_EQ(l.background.environment, map);
    EXPECT_EQ(l.environment.map, map);
    EXPECT_TRUE(l.environment.radiance.empty());  // projected from the map
    const json back = protocol::lightingToJson(l, map.get());
    EXPECT_EQ(back["background"]["environment"], "session");
    EXPECT_EQ(back["background"]["color"], json::array({0.1, 0.2, 0.3}));
    EXPECT_EQ(back["environment"]["map"], "session");
    ASSERT_EQ(back["environment"]["radiance"].size(), 4u);
    EXPECT_NEAR(back["environment"]["radiance"][2][0].get<double>(), 0.5, 1e-6);
    // Read back, the written radiances are the fallback when there is no map (a damaged file).
    protocol::LightingRequest again = protocol::lightingFromJson(back);
    again.backgroundUsesSessionMap = again.environmentUsesSessionMap = false;
    EXPECT_NEAR(again.resolve(nullptr).environment.radiance[1].y, 0.5, 1e-6);
    // Without the session's map to compare with, a map is not written as "session".
    EXPECT_TRUE(protocol::lightingToJson(l)["background"].is_array());
}

TEST(LightingJson, MapsThatAreNotLatLongAreRefusedNamingTheField) {
    core::Lighting l;
    l.background.environment = std::make_shared<core::Image>(16, 16);
    l.environment.lobes = 4;
    l.environment.map = std::make_shared<core::Image>(30, 10);
    std::set<std::string> fields;
    for (const auto& p : l.check()) fields.insert(p.field);
    EXPECT_EQ(fields, (std::set<std::string>{"background/environment", "environment/map"}));
    core::Image negative(8, 4);
    negative.pixel(1, 1)[2] = -0.5f;
    EXPECT_NE(core::latLongMapProblem(negative).find("negative"), std::string::npos);
    negative.pixel(1, 1)[2] = std::nanf("");
    EXPECT_NE(core::latLongMapProblem(negative).find("non-finite"), std::string::npos);
    EXPECT_EQ(core::latLongMapProblem(core::Image(9, 4)), "");  // one pixel of slack
}

TEST(LightingJson, TheLobesAsTheBackground) {
    const json j = {{"background", {{"color", {0.1, 0.1, 0.1}}, {"environment", "lobes"}}},
                    {"environment", {{"lobes", 2}, {"radiance", {{1, 1, 1}, {2, 2, 2}}}}}};
    const core::Lighting l = protocol::lightingFromJson(j).lighting;  // API and CLI alike
    EXPECT_TRUE(l.background.fromLobes);
    EXPECT_FALSE(protocol::lightingFromJson(j, "", true).environmentPath.has_value());  // not a file
    EXPECT_EQ(protocol::lightingToJson(l)["background"]["environment"], "lobes");
    // Without an environment light there are no lobes to show.
    std::set<std::string> paths;
    for (const auto& e : errorsOf([&] { protocol::lightingFromJson({{"background", {{"environment", "lobes"}}}}); })) paths.insert(e.path);
    EXPECT_EQ(paths, (std::set<std::string>{"/background/environment"}));
}

TEST(TranslucentJson, PerturbationRoundTripsAndNamesBadFields) {
    const json j = {{"slice_spacing", 0.5},
                    {"perturbation", {{"amplitude", 2}, {"frequency", 12}, {"octaves", 4}, {"property_amplitude", 0.25}, {"seed", 9}, {"time", 1.5}}}};
    const core::TranslucentSettings s = protocol::translucentFromJson(j);
    EXPECT_EQ(s.perturbation.octaves, 4);
    EXPECT_EQ(s.perturbation.seed, 9u);
    const core::TranslucentSettings back = protocol::translucentFromJson(protocol::translucentToJson(s));
    EXPECT_EQ(back.perturbation.amplitude, 2);
    EXPECT_EQ(back.perturbation.time, 1.5);
    EXPECT_EQ(back.sliceSpacing, 0.5);
    std::set<std::string> paths;
    for (const auto& e : errorsOf([&] {
             protocol::translucentFromJson({{"perturbation", {{"amplitude", -1}, {"octaves", 9}, {"seed", -3}, {"colour", 1}}}});
         }))
        paths.insert(e.path);
    EXPECT_EQ(paths, (std::set<std::string>{"/perturbation/amplitude", "/perturbation/octaves", "/perturbation/seed", "/perturbation/colour"}));
}

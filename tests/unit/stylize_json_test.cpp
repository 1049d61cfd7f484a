// The stylizer's scene JSON (SPEC §7): fields, column-major transforms, every problem at once.
#include <gtest/gtest.h>

#include "protocol/stylize_json.h"

using namespace volstyle;
using nlohmann::json;

namespace {

/// Expects `j` to be refused with a problem at every one of `expected` (JSON Pointers).
void expectProblemsAt(const json& j, std::initializer_list<const char*> expected) {
    try {
        protocol::stylizerSceneFromJson(j);
        FAIL() << "expected a ValidationError";
    } catch (const protocol::ValidationError& e) {
        std::string paths;
        for (const auto& d : e.details()) paths += d.path + " ";
        for (const char* path : expected) EXPECT_NE(paths.find(std::string(path) + " "), std::string::npos) << path << " in " << paths;
    }
}

}  // namespace

TEST(StylizeJson, ReadsTheSceneWithAColumnMajorTransform) {
    const json j = json::parse(R"({
      "occluders": [{"name": "tree", "mesh": "tree.obj", "colour": [0.2, 0.3, 0.1],
                     "manipulation": {"closing": {"radius_px": 6, "shape": "box"}},
                     "transform": [2,0,0,0, 0,2,0,0, 0,0,2,0, 1,2,3,1]}],
      "light": {"type": "directional", "direction": [0, 1, 0], "irradiance": [1, 2, 3], "shadow_map_size": 1024},
      "medium": {"extinction": 0.2, "albedo": 0.5, "phase": {"type": "isotropic"}},
      "camera": {"eye": [0, 1, 5], "target": [0, 1, 0], "width": 64, "height": 32},
      "background": [0.1, 0.1, 0.1], "time": 1.5})");
    const protocol::StylizerSceneRequest r = protocol::stylizerSceneFromJson(j);
    ASSERT_EQ(r.scene.occluders.size(), 1u);
    EXPECT_EQ(r.meshRefs[0], "tree.obj");
    EXPECT_EQ(r.scene.occluders[0].name, "tree");
    const Mat4& m = r.scene.occluders[0].worldFromObject;
    EXPECT_EQ(m(0, 0), 2);
    EXPECT_EQ(m(0, 3), 1);  // the translation is the last column
    EXPECT_EQ(m(1, 3), 2);
    EXPECT_EQ(m(2, 3), 3);
    EXPECT_EQ(r.scene.occluders[0].manipulation.closingRadius, 6);
    EXPECT_EQ(r.scene.occluders[0].manipulation.closingShape, core::MorphShape::Box);
    EXPECT_EQ(r.scene.light.shadowMapSize, 1024);
    EXPECT_EQ(r.scene.medium.phase.type, core::PhaseType::Isotropic);
    EXPECT_EQ(r.scene.camera.width, 64);
    EXPECT_EQ(r.scene.time, 1.5);
}

TEST(StylizeJson, EveryProblemAtOnceUnderItsPath) {
    const json j = json::parse(R"({
      "occluders": [{"transform": [1, 2, 3], "colour": [2, 0, 0], "manipulation": {"closing": {"radius_px": 99}, "holes": {}}}],
      "light": {"shadow_map_size": 100, "direction": [0, 0, 0]},
      "medium": {"extinction": -1},
      "camera": {"eye": [0, 0, 0], "target": [0, 0, 0]},
      "transfer_function": {}, "extra": 1})");
    expectProblemsAt(j, {"/occluders/0/mesh", "/occluders/0/transform", "/occluders/0/colour",
                         "/occluders/0/manipulation/closing/radius_px", "/occluders/0/manipulation/holes/probability", "/light/shadow_map_size", "/light/direction",
                         "/medium/extinction", "/camera/target", "/transfer_function/image", "/extra"});
}

TEST(StylizeJson, DilationHolesAndSpotLights) {
    const json j = json::parse(R"({
      "occluders": [{"mesh": "a.obj", "manipulation": {"dilation": {"length": 0.3, "erosion_px": 2},
                     "holes": {"frequency": 0.5, "probability": 0.4, "seed": 9, "speed": 0.25, "octaves": 3, "persistence": 0.6}}}],
      "light": {"type": "spot", "position": [1, 8, 2], "direction": [0, 1, 0], "cone_deg": 40}})");
    const auto r = protocol::stylizerSceneFromJson(j);
    const core::Manipulation& m = r.scene.occluders[0].manipulation;
    EXPECT_EQ(m.dilationLength, 0.3);
    EXPECT_EQ(m.erosionPx, 2);
    EXPECT_EQ(m.holeFrequency, 0.5);
    EXPECT_EQ(m.holeProbability, 0.4);
    EXPECT_EQ(m.holeSeed, 9u);
    EXPECT_EQ(m.holeSpeed, 0.25);
    EXPECT_EQ(m.holeOctaves, 3);
    EXPECT_EQ(m.holePersistence, 0.6);
    EXPECT_EQ(r.scene.light.type, core::StylizerLightType::Spot);
    EXPECT_EQ(r.scene.light.position.y, 8);
    EXPECT_EQ(r.scene.light.coneDeg, 40);
}

TEST(StylizeJson, BadEditsAndLightsAreNamed) {
    const json j = json::parse(R"({
      "occluders": [{"mesh": "a.obj", "manipulation": {"dilation": {"erosion_px": 99},
                     "holes": {"probability": 1.5, "frequency": 0, "seed": 0.5, "octaves": 20, "wind": 1}}}],
      "light": {"type": "spot", "cone_deg": 170}, "time": 1e300})");
    expectProblemsAt(j, {"/occluders/0/manipulation/dilation/length", "/occluders/0/manipulation/dilation/erosion_px",
                         "/occluders/0/manipulation/holes/probability", "/occluders/0/manipulation/holes/frequency",
                         "/occluders/0/manipulation/holes/seed", "/occluders/0/manipulation/holes/octaves",
                         "/occluders/0/manipulation/holes/wind", "/light/position", "/light/cone_deg", "/time"});
    // A directional light with a spot's fields is a typo, not a silent default.
    try {
        protocol::stylizerSceneFromJson(json::parse(R"({"light": {"position": [0, 1, 0]}})"));
        FAIL() << "expected a ValidationError";
    } catch (const protocol::ValidationError& e) {
        EXPECT_EQ(e.details().at(0).path, "/light/position");
    }
}

// The stylizer's scene JSON (SPEC §7): fields, column-major transforms, every problem at once.
#include <gtest/gtest.h>

#include "protocol/stylize_json.h"

using namespace volstyle;
using nlohmann::json;

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
    try {
        protocol::stylizerSceneFromJson(j);
        FAIL() << "expected a ValidationError";
    } catch (const protocol::ValidationError& e) {
        std::string paths;
        for (const auto& d : e.details()) paths += d.path + " ";
        for (const char* expected : {"/occluders/0/mesh", "/occluders/0/transform", "/occluders/0/colour",
                                     "/occluders/0/manipulation/closing/radius_px", "/occluders/0/manipulation/holes", "/light/shadow_map_size", "/light/direction",
                                     "/medium/extinction", "/camera/target", "/transfer_function/image", "/extra"})
            EXPECT_NE(paths.find(std::string(expected) + " "), std::string::npos) << expected << " in " << paths;
    }
}

// The API schema states the same ranges as the one check() of each core value (issue #36): a
// range changed in C++ and not in protocol/schema/v1.json (or the other way) fails here.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/stylize/scene.h"
#include "protocol/requests.h"
#include "protocol/validation.h"

namespace volstyle {
namespace {

using nlohmann::json;

const json& schema() {
    static const json s = json::parse(protocol::kSchemaV1);
    return s;
}

/// The schema of a property: definitions/TYPE/properties/A/properties/B/…
const json& property(const std::string& type, std::initializer_list<const char*> path) {
    const json* at = &schema().at("definitions").at(type);
    for (const char* name : path) at = &at->at("properties").at(name);
    return *at;
}

TEST(SchemaLimits, TheSolveStepIsTheMarchStepsRange) {
    const json& step = property("solve_options", {"step"});
    EXPECT_EQ(step.at("minimum").get<double>(), core::kMinStepVoxels);
    EXPECT_EQ(step.at("maximum").get<double>(), core::kMaxStepVoxels);
    // And the one check says so.
    EXPECT_FALSE(core::stepProblem(core::kMinStepVoxels));
    EXPECT_FALSE(core::stepProblem(core::kMaxStepVoxels));
    EXPECT_TRUE(core::stepProblem(core::kMinStepVoxels * 0.99));
    EXPECT_TRUE(core::stepProblem(core::kMaxStepVoxels * 1.01));
}

TEST(SchemaLimits, TheStylizerManipulationRangesAreTheScenes) {
    const json& closing = property("stylizer_manipulation", {"closing", "radius_px"});
    EXPECT_EQ(closing.at("minimum").get<int>(), 0);
    EXPECT_EQ(closing.at("maximum").get<int>(), core::kMaxClosingRadiusPx);
    const json& erosion = property("stylizer_manipulation", {"dilation", "erosion_px"});
    EXPECT_EQ(erosion.at("maximum").get<int>(), core::kMaxErosionPx);
    EXPECT_EQ(property("stylizer_manipulation", {"dilation", "length"}).at("maximum").get<double>(), core::kMaxDilationLength);
    EXPECT_EQ(property("stylizer_manipulation", {"holes", "frequency"}).at("maximum").get<double>(), core::kMaxHoleFrequency);
    EXPECT_EQ(property("stylizer_manipulation", {"holes", "speed"}).at("maximum").get<double>(), core::kMaxHoleSpeed);
    EXPECT_EQ(property("stylizer_manipulation", {"holes", "speed"}).at("minimum").get<double>(), -core::kMaxHoleSpeed);
    EXPECT_EQ(property("stylizer_manipulation", {"holes", "octaves"}).at("minimum").get<int>(), core::kMinHoleOctaves);
    EXPECT_EQ(property("stylizer_manipulation", {"holes", "octaves"}).at("maximum").get<int>(), core::kMaxHoleOctaves);
    // Each bound is where Manipulation::check() starts to object, with the field's path.
    core::Manipulation m;
    m.closingRadius = core::kMaxClosingRadiusPx;
    EXPECT_TRUE(m.check().empty());
    m.closingRadius = core::kMaxClosingRadiusPx + 1;
    ASSERT_EQ(m.check().size(), 1u);
    EXPECT_EQ(m.check()[0].field, "closing/radius_px");
    m.closingRadius = 0;
    m.holeOctaves = core::kMaxHoleOctaves + 1;
    m.erosionPx = -1;
    EXPECT_EQ(m.check().size(), 2u);
}

TEST(SchemaLimits, EveryExposureIsTheRequestsRange) {
    for (const char* type : {"render_request", "frames_render_request", "stylizer_frame_request", "stylizer_sequence_request"}) {
        const json& exposure = property(type, {"exposure"});
        EXPECT_EQ(exposure.at("minimum").get<double>(), -protocol::kMaxExposureStops) << type;
        EXPECT_EQ(exposure.at("maximum").get<double>(), protocol::kMaxExposureStops) << type;
    }
    EXPECT_EQ(protocol::exposureProblem(protocol::kMaxExposureStops), "");
    EXPECT_EQ(protocol::exposureProblem(-protocol::kMaxExposureStops - 0.5), "must be in [-30, 30] stops");
}

}  // namespace
}  // namespace volstyle

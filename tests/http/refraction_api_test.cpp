// Refraction over the API (issue #16): POST …/refraction generates a glass sphere's refractive
// index (the TVCG paper's Fig. 8) into a new version, renders and solves then follow the bent
// rays, DELETE removes the grid (renders are the straight ones again, bit for bit); bad fields are
// refused by name with the volume untouched.
#include <gtest/gtest.h>

#include <set>

#include "api_fixture.h"
#include "core/image/image_io.h"

using namespace volstyle;
using namespace volstyle::test;

namespace {

class RefractionApi : public Api {};

core::Image decodeImage(const httplib::Result& r) {
    EXPECT_EQ(r->status, 200) << r->body;
    return core::loadImageFromMemory(r->body.data(), r->body.size(), "answer").image;
}

bool hasGrid(const json& session, const std::string& grid) {
    for (const auto& g : session["volume"]["grids"])
        if (g == grid) return true;
    return false;
}

}  // namespace

TEST_F(RefractionApi, AGlassSphereIsGeneratedRenderedSolvedAndRemoved) {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    json e = expectError(client().Post((base + "/refraction").c_str(), R"({"index": 5, "noise": -1, "radius": 0})", "application/json"), 400,
                         "invalid_argument");
    std::set<std::string> paths;
    for (const auto& d : e["error"]["details"]) paths.insert(d["path"].get<std::string>());
    EXPECT_EQ(paths, (std::set<std::string>{"/index", "/noise", "/radius"}));
    expectError(client().Post((base + "/refraction").c_str(), R"({"index": 1.2, "colour": 1})", "application/json"), 400, "unknown_field");
    expectError(client().Delete((base + "/refraction").c_str()), 400, "invalid_argument");  // nothing to remove
    EXPECT_EQ(json::parse(client().Get(base.c_str())->body)["volume"]["version"], 1) << "refused requests change nothing";

    const json camera = {{"camera", {{"eye", {0.3, 0.2, 3}}, {"target", {0, 0, 0}}, {"width", 24}, {"height", 24}}}};
    auto render = [&] { return client().Post((base + "/render").c_str(), camera.dump(), "application/json"); };
    const auto straight = render();
    ASSERT_EQ(straight->status, 200);

    auto r = client().Post((base + "/refraction").c_str(), R"({"index": 1.45, "radius": 0.7, "noise": 0.05, "seed": 2})", "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    json s = json::parse(r->body);
    EXPECT_EQ(s["volume"]["version"], 2);
    EXPECT_TRUE(hasGrid(s, "refractive_index"));
    const core::Image a = decodeImage(straight), b = decodeImage(render());
    double moved = 0;
    for (size_t i = 0; i < a.rgba.size(); ++i) moved = std::max(moved, double(std::abs(a.rgba[i] - b.rgba[i])));
    EXPECT_GT(moved, 0.05) << "the glass bends what the camera sees";

    // An extinction solve through it (masks of a constant medium radiance).
    addConstantTargetView(client(), base, 16, 0.5f);
    const json job = solveToEnd(client(), base, R"({"unknowns": ["extinction"], "medium_radiance": [1, 1, 1], "max_iterations": 5})");
    EXPECT_EQ(job["state"], "done") << job.dump();
    EXPECT_EQ(job["result"]["version"], 3);
    EXPECT_TRUE(hasGrid(json::parse(client().Get(base.c_str())->body), "refractive_index")) << "the solved version keeps its glass";

    r = client().Delete((base + "/refraction").c_str());
    ASSERT_EQ(r->status, 200) << r->body;
    s = json::parse(r->body);
    EXPECT_EQ(s["volume"]["version"], 4);
    EXPECT_FALSE(hasGrid(s, "refractive_index"));
    ASSERT_EQ(client().Post((base + "/revert").c_str(), R"({"version": 1})", "application/json")->status, 200);
    EXPECT_EQ(render()->body, straight->body) << "without the grid, the straight render bit for bit";
}

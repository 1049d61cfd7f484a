// A sparse session volume over the API (issue #39): an uploaded VDB stored as bricks renders,
// takes a glass sphere (refraction), bakes a perturbation and is the stylizer's medium, as a dense
// one does — each route answers 200 and keeps it sparse.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "../common/image_compare.h"
#include "stylizer_fixture.h"

using namespace volstyle;
using json = nlohmann::json;

namespace {

class SparseApi : public test::StylizerApi {};

std::string readFile(const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

bool hasGrid(const json& session, const std::string& name) {
    for (const auto& g : session["volume"]["grids"])
        if (g == name) return true;
    return false;
}

}  // namespace

TEST_F(SparseApi, ASparseVolumeRendersRefractsPerturbsAndIsTheStylizersMedium) {
    m_maxUploadBytes = 1 << 20;
    TearDown();
    server::ServerOptions opt;
    opt.volumeLimits.storage = core::VolumeStorage::Sparse;  // every volume stored as bricks
    start(opt);
    const std::string session = "/api/v1/sessions/" + createSession();
    base = session + "/stylizer";
    auto r = client().Put((session + "/volume").c_str(), readFile(VOLSTYLE_SOURCE_DIR "/tests/data/files/houdini-like.vdb"),
                          "application/octet-stream");
    ASSERT_EQ(r->status, 200) << r->body;
    json s = json::parse(r->body);
    ASSERT_EQ(s["volume"]["storage"], "sparse");
    const auto lo = s["volume"]["bbox"][0].get<std::vector<double>>(), hi = s["volume"]["bbox"][1].get<std::vector<double>>();
    const std::vector<double> centre{(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
    const json camera = {{"camera", {{"eye", {centre[0] + 0.2, centre[1] + 0.3, centre[2] + 4}}, {"target", centre}, {"width", 24}, {"height", 24}}},
                         {"format", "exr"}};
    auto render = [&] {
        auto q = client().Post((session + "/render").c_str(), camera.dump(), "application/json");
        EXPECT_EQ(q->status, 200) << q->body;
        return core::loadImageFromMemory(q->body.data(), q->body.size(), "render").image;
    };
    const core::Image plain = render();

    // Refraction: a glass sphere over the middle of the box, in the bricks it reaches.
    r = client().Post((session + "/refraction").c_str(), R"({"index": 1.4, "radius": 0.5, "noise": 0})", "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    s = json::parse(r->body);
    EXPECT_TRUE(hasGrid(s, "refractive_index"));
    EXPECT_EQ(s["volume"]["storage"], "sparse");
    const core::Image bent = render();
    EXPECT_GT(test::maxAbsDifference(plain, bent), 1e-3) << "the glass bends the view";

    // A perturbation baked in: the bricks grow by its reach, the volume stays sparse.
    const size_t before = s["volume"]["active_voxels"];
    r = client().Post((session + "/perturb").c_str(), R"({"amplitude": 3, "frequency": 6, "seed": 3})", "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    s = json::parse(r->body);
    EXPECT_EQ(s["volume"]["storage"], "sparse");
    EXPECT_GT(s["volume"]["active_voxels"].get<size_t>(), before);
    const core::Image moved = render();
    EXPECT_GT(test::maxAbsDifference(bent, moved), 1e-4) << "the medium moved";

    // The stylizer's heterogeneous medium from the session's sparse volume.
    json scene = smallForest();
    scene.erase("transfer_function");
    ASSERT_EQ(putScene(scene)->status, 200);
    const core::Image homogeneous = frame();
    scene["volume"] = {{"extinction_scale", 2.0}, {"box", {{-6, 0, -6}, {4, 6, 2}}}};
    r = putScene(scene);
    ASSERT_EQ(r->status, 200) << r->body;
    const core::Image withVolume = frame();
    for (float v : withVolume.rgba) ASSERT_TRUE(std::isfinite(v));
    EXPECT_GT(test::maxAbsDifference(homogeneous, withVolume), 1e-3) << "the sparse medium changed the frame";
}

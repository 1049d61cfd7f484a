// Pipeline-grade files over the API (issue #10): a VDB uploaded the way curl sends it comes back
// with everything it had, EXR renders carry their compositing layers (and as a view's target mean
// the picture they show, issue #34), and a solve that cannot start says how to fix it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "api_fixture.h"
#include "core/volume/vdb_io.h"

using namespace volstyle;
using json = nlohmann::json;
using volstyle::test::addConstantTargetView;

namespace {

class Files : public test::Api {};

std::string readFile(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

/// A file as Houdini writes one: float `density` at an index offset, a float `albedo`,
/// `temperature` and a staggered `vel` volstyle does not use, grid and file metadata, a tile.
const std::filesystem::path kHoudiniLike = VOLSTYLE_SOURCE_DIR "/tests/data/files/houdini-like.vdb";

}  // namespace

TEST_F(Files, AnUploadedVdbComesBackWithEverythingItHad) {
    m_maxUploadBytes = 1 << 20;
    TearDown();
    start();
    const std::string id = createSession();
    const std::string base = "/api/v1/sessions/" + id;
    // curl --data-binary sends application/x-www-form-urlencoded: accepted, recognised by its bytes.
    auto r = client().Put((base + "/volume").c_str(), readFile(kHoudiniLike), "application/x-www-form-urlencoded");
    ASSERT_EQ(r->status, 200) << r->body;
    const json session = json::parse(r->body);
    EXPECT_EQ(session["scene"], "upload") << "the session must not claim its first scene any more";

    const auto dir = std::filesystem::temp_directory_path() / ("volstyle-files-" + id);
    std::filesystem::create_directories(dir);
    auto d = client().Get((base + "/volume.vdb").c_str());
    ASSERT_EQ(d->status, 200);
    std::ofstream((dir / "back.vdb").string(), std::ios::binary) << d->body;
    const auto lost = core::vdbDifferences(kHoudiniLike.string(), (dir / "back.vdb").string());
    EXPECT_TRUE(lost.empty()) << lost.front();
    std::filesystem::remove_all(dir);
}

TEST_F(Files, ExrRendersCarryTheirLayersAndPngsThePicture) {
    const std::string base = "/api/v1/sessions/" + createSession();
    const json camera = {{"eye", {0, 0.3, 3}}, {"target", {0, 0, 0}}, {"width", 16}, {"height", 16}};
    auto exr = client().Post((base + "/render").c_str(), json{{"camera", camera}, {"format", "exr"}}.dump(), "application/json");
    ASSERT_EQ(exr->status, 200) << exr->body;
    EXPECT_EQ(exr->body.substr(0, 4), std::string("\x76\x2f\x31\x01", 4));
    for (const char* channel : {"background.R", "emission.R", "scattering.G", "transmittance.B"})
        EXPECT_NE(exr->body.find(std::string(channel) + '\0'), std::string::npos) << channel;
    auto png = client().Post((base + "/render").c_str(), json{{"camera", camera}, {"format", "png"}}.dump(), "application/json");
    ASSERT_EQ(png->status, 200);
    EXPECT_EQ(png->body.substr(1, 3), "PNG");
}

TEST_F(Files, AnExtinctionSolveWithoutMediumRadianceSuggestsTheBackground) {
    const std::string base = "/api/v1/sessions/" + createSession();
    addConstantTargetView(client(), base, 8, 0.5f);
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), R"({"background": [0.25, 0.5, 0.75]})", "application/json")->status, 200);
    json e = expectError(client().Post((base + "/solve").c_str(), R"({"unknowns": ["extinction"]})", "application/json"), 400,
                         "invalid_argument");
    ASSERT_FALSE(e["error"]["details"].empty()) << e;
    EXPECT_EQ(e["error"]["details"][0]["path"], "/medium_radiance");
    EXPECT_NE(e["error"]["details"][0]["message"].get<std::string>().find("\"medium_radiance\": [0.25, 0.5, 0.75]"),
              std::string::npos)
        << e;
}

TEST_F(Files, ARendersExrAsATargetIsThePictureItShows) {
    // Issue #34: a view's own render EXR uploaded as its target means RGB + T·background with
    // weight 1 — as its PNG render shows it — not the medium alone weighted by its coverage.
    const std::string id = createSession(), base = "/api/v1/sessions/" + id;
    auto v = client().Post((base + "/views").c_str(), R"({"camera":{"eye":[0,0,3],"target":[0,0,0],"width":24,"height":20}})",
                           "application/json");
    ASSERT_EQ(v->status, 201) << v->body;
    const std::string view = json::parse(v->body)["id"];
    auto exr = client().Get((base + "/views/" + view + "/render.exr?exr_type=float").c_str());
    ASSERT_EQ(exr->status, 200);
    EXPECT_GT(exr->body.size(), client().Get((base + "/views/" + view + "/render.exr").c_str())->body.size() * 3 / 2) << "float, not half";
    expectError(client().Get((base + "/views/" + view + "/render.exr?exr_type=int").c_str()), 400, "invalid_argument");
    auto put = client().Put((base + "/views/" + view + "/target").c_str(), exr->body, "image/x-exr");
    ASSERT_EQ(put->status, 200) << put->body;
    const core::LoadedImage rendered = core::loadImageFromMemory(exr->body.data(), exr->body.size(), "render");
    const core::Image picture = core::pictureOf(rendered);
    auto back = client().Get((base + "/views/" + view + "/target.png").c_str());
    ASSERT_EQ(back->status, 200) << back->body;
    const core::Image target = core::loadImageFromMemory(back->body.data(), back->body.size(), "target").image;
    double worst = 0, background = 0;
    for (size_t i = 0; i < picture.pixelCount(); ++i) {
        for (size_t c = 0; c < 3; ++c)
            worst = std::max(worst, double(std::abs(target.rgba[4 * i + c] - std::min(1.0f, picture.rgba[4 * i + c]))));
        EXPECT_EQ(target.rgba[4 * i + 3], 1.0f) << "weight 1, not coverage";
        background = std::max(background, double(rendered.background.rgba[4 * i]));
    }
    EXPECT_GT(background, 0.05) << "the session's background shows through";
    EXPECT_LE(worst, 0.01) << "the stored target is the picture (8-bit sRGB: 0.01)";
}

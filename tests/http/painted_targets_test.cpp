// Paint that means what it shows (issue #37): the same strokes painted over a view's 8-bit PNG
// render (whose bright pixels clipped to white; the server leaves those out) and over its linear
// EXR render (the page's way: true values everywhere) solve to the same volume within a stated
// tolerance, though the PNG lost its clipped pixels and rounded the rest to 8 bits: the voxels'
// change within 15% (measured 10.0%), the pictures from the painted view and from an unpainted
// side view within 8% of how far the solve moved them (measured 5.7% and 4.7%). The paint's
// colour has a channel at 255 and must keep its weight (a rule that read any 255 as clipped
// dropped the whole stroke).
#include <cmath>
#include <fstream>
#include <tuple>

#include "api_fixture.h"
#include "core/image/image.h"
#include "core/volume/vdb_io.h"

namespace volstyle::test {
namespace {

class PaintedTargets : public Api {};

constexpr int kPixels = 48;
constexpr const char* kFront = R"({"eye": [0, 0.2, 3.4], "target": [0, -0.05, 0], "fov_y_deg": 38, "width": 48, "height": 48})";
constexpr const char* kSide = R"({"eye": [3.4, 0.2, 0], "target": [0, -0.05, 0], "fov_y_deg": 38, "width": 48, "height": 48})";  // unpainted

/// The session's volume (a version, or the current one) as the server writes it.
core::Volume volumeOf(httplib::Client& c, const std::string& sid, int version = 0) {
    auto r = c.Get(("/api/v1/sessions/" + sid + "/volume.vdb" + (version ? "?version=" + std::to_string(version) : "")).c_str());
    EXPECT_EQ(r->status, 200);
    const std::string path = std::filesystem::temp_directory_path() / ("volstyle_painted_" + sid + ".vdb");
    std::ofstream(path, std::ios::binary) << r->body;
    core::Volume v = core::loadVdb(path);
    std::filesystem::remove(path);
    return v;
}

/// The unknowns' change from `before`: emission then albedo, every voxel and channel.
std::vector<double> change(const core::Volume& after, const core::Volume& before) {
    std::vector<double> d;
    for (size_t i = 0; i < after.voxelCount() * 3; ++i) {
        d.push_back(double(after.emission().empty() ? 0.0f : after.emission()[i]) - (before.emission().empty() ? 0.0 : before.emission()[i]));
        d.push_back(double(after.albedo()[i]) - (before.hasAlbedo() ? before.albedo()[i] : 1.0));
    }
    return d;
}

double norm(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x * x;
    return std::sqrt(s);
}

/// What a camera sees of the session's volume now: the picture of a float EXR render.
core::Image pictureFrom(httplib::Client& c, const std::string& sid, const std::string& camera) {
    auto r = c.Post(("/api/v1/sessions/" + sid + "/render").c_str(), R"({"format": "exr", "exr_type": "float", "camera": )" + camera + "}",
                    "application/json");
    EXPECT_EQ(r->status, 200) << r->body;
    return core::pictureOf(core::loadImageFromMemory(r->body.data(), r->body.size(), "render.exr"));
}

/// RMS over pixels and channels of a − b.
double rmsDifference(const core::Image& a, const core::Image& b) {
    double s = 0;
    for (size_t i = 0; i < a.pixelCount(); ++i)
        for (size_t c = 0; c < 3; ++c) s += std::pow(double(a.rgba[4 * i + c]) - b.rgba[4 * i + c], 2);
    return std::sqrt(s / double(3 * a.pixelCount()));
}

/// Solves the session's one view toward `target` (uploaded as it is) and returns the change.
std::vector<double> solveToward(httplib::Client& c, const std::string& sid, const std::string& target, const std::string& type,
                                int& clipped) {
    const std::string base = "/api/v1/sessions/" + sid;
    auto r = c.Put((base + "/views/v1/target").c_str(), target, type);
    EXPECT_EQ(r->status, 200) << r->body;
    clipped = json::parse(r->body)["clipped_pixels"];
    r = c.Post((base + "/solve").c_str(), R"({"unknowns": ["emission", "albedo"], "max_iterations": 40, "tolerance": 0})", "application/json");
    EXPECT_EQ(r->status, 202) << r->body;
    const std::string job = json::parse(r->body)["job"];
    EXPECT_EQ(readEvents(c, "/api/v1/jobs/" + job + "/events").back(), "done");
    return change(volumeOf(c, sid), volumeOf(c, sid, 1));
}

TEST_F(PaintedTargets, ThePngAndTheExrWorkflowReachTheSameVolume) {
    // Two identical sessions, one view each: the 24³ cloud under the default lighting (sun 26).
    std::string sids[2];
    for (std::string& sid : sids) {
        auto r = client().Post("/api/v1/sessions", R"({"scene": "builtin:cloud", "resolution": 24})", "application/json");
        ASSERT_EQ(r->status, 201) << r->body;
        sid = json::parse(r->body)["id"];
        ASSERT_EQ(client().Post(("/api/v1/sessions/" + sid + "/views").c_str(), std::string(R"({"camera": )") + kFront + "}", "application/json")->status,
                  201);
    }
    const std::string view = "/api/v1/sessions/" + sids[0] + "/views/v1";
    auto png = client().Get((view + "/render.png").c_str());
    auto exr = client().Get((view + "/render.exr?exr_type=float").c_str());
    ASSERT_EQ(png->status, 200);
    ASSERT_EQ(exr->status, 200);
    core::LoadedImage pngBase = core::loadImageFromMemory(png->body.data(), png->body.size(), "render.png");
    const core::Image exrBase = core::pictureOf(core::loadImageFromMemory(exr->body.data(), exr->body.size(), "render.exr"));

    // The strokes: an opaque disc of #ffb060 (an sRGB colour the PNG holds exactly) in the middle.
    core::Image pngPainted = pngBase.image, exrPainted = exrBase;
    const float paint[3] = {1.0f, core::srgbToLinear(0xb0 / 255.0f), core::srgbToLinear(0x60 / 255.0f)};
    int painted = 0;
    for (int y = 0; y < kPixels; ++y)
        for (int x = 0; x < kPixels; ++x) {
            exrPainted.pixel(x, y)[3] = pngPainted.pixel(x, y)[3] = 1;
            if (std::hypot(x - 23.5, y - 25.5) > 9) continue;
            for (int c = 0; c < 3; ++c) pngPainted.pixel(x, y)[c] = exrPainted.pixel(x, y)[c] = paint[c];
            ++painted;
        }
    core::SaveOptions asPng, asExr;
    asPng.writeAlpha = true;
    asExr.halfFloat = false;
    const core::Image sideBefore = pictureFrom(client(), sids[0], kSide);
    int clipped[2] = {0, 0};
    const auto dPng = solveToward(client(), sids[0], core::encodeImage(pngPainted, "png", asPng), "image/png", clipped[0]);
    const auto dExr = solveToward(client(), sids[1], core::encodeImage(exrPainted, "exr", asExr), "image/x-exr", clipped[1]);

    EXPECT_GT(clipped[0], 0) << "the PNG's base clips under the default lighting (the case under test)";
    EXPECT_EQ(clipped[1], 0) << "a float target has no clipped pixels";
    std::vector<double> gap(dPng.size());
    for (size_t i = 0; i < gap.size(); ++i) gap[i] = dPng[i] - dExr[i];
    const double relative = norm(gap) / norm(dExr);
    std::printf("[ measured ] %d painted pixels, %d clipped (PNG): the volumes' changes differ by %.2f%% of the EXR workflow's change "
                "(|change| %.4g vs %.4g)\n",
                painted, clipped[0], 100 * relative, norm(dPng), norm(dExr));
    EXPECT_GT(norm(dExr), 1.0) << "the paint moved the volume";
    // One view of 48² pixels against 6 × 24³ unknowns: what the view does not pin down moves with
    // the PNG's 8-bit rounding (its share, measured alone: 6%) and its 23 clipped pixels.
    EXPECT_LT(relative, 0.15) << "the PNG and EXR workflows solve to the same volume within 15% of the change (measured 10.0%)";

    // What the volumes look like: from the painted view and from the side (never painted), the
    // two workflows' renders differ by a small share of how far the solve moved the picture.
    for (const auto& [name, camera, before] : {std::tuple{"painted view", kFront, exrBase}, std::tuple{"side view", kSide, sideBefore}}) {
        const core::Image a = pictureFrom(client(), sids[0], camera), b = pictureFrom(client(), sids[1], camera);
        const double share = rmsDifference(a, b) / rmsDifference(b, before);
        std::printf("[ measured ] %s: the workflows' renders differ by RMS %.4g, %.2f%% of the solve's change to it (RMS %.4g)\n", name,
                    rmsDifference(a, b), 100 * share, rmsDifference(b, before));
        EXPECT_LT(share, 0.08) << name << " (measured 5.7% painted, 4.7% side)";
    }
}

}  // namespace
}  // namespace volstyle::test

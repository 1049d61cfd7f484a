// An animation over the API (issue #16): frames uploaded as VDBs (one grid for all), views tied to
// frames, POST …/animate solving the key frames as a job and storing every frame, frames
// downloaded as VDBs and rendered to PNG by a job; frames and views' frames survive a restart.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <unistd.h>

#include "api_fixture.h"
#include "core/image/image_io.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"

using namespace volstyle;
using namespace volstyle::test;

namespace {

/// Frame f: a ball of smoke moving +0.3 along x per frame (16³).
std::string ballFrame(int f, int res = 16) {
    const Int3 dims{res, res, res};
    core::Volume v(dims, core::unitBoxWorldFromIndex(dims));
    for (int k = 0; k < res; ++k)
        for (int j = 0; j < res; ++j)
            for (int i = 0; i < res; ++i) {
                const Vec3d x = v.worldFromIndex().applyPoint({double(i), double(j), double(k)});
                const bool in = length(x - Vec3d(-0.3 + 0.3 * f, 0, 0)) < 0.45;
                v.setExtinction(i, j, k, Vec3(in ? 3.0f : 0.0f));
            }
    const auto path = std::filesystem::temp_directory_path() / ("volstyle-ball-" + std::to_string(::getpid()) + ".vdb");
    core::saveVdb(path.string(), v);
    std::ifstream in(path, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    std::filesystem::remove(path);
    return bytes.str();
}

class AnimationApi : public PersistentApi {
protected:
    std::vector<core::Volume> animateTheBall();
    std::vector<std::string> m_storage;  ///< each frame's storage after animateTheBall, as GET …/frames says
};

}  // namespace

TEST_F(AnimationApi, KeyFramesAreSolvedStoredRenderedAndKept) {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    for (int f = 0; f <= 2; ++f) {
        auto r = client().Put((base + "/frames/" + std::to_string(f)).c_str(), ballFrame(f), "application/octet-stream");
        ASSERT_EQ(r->status, 200) << r->body;
    }
    json frames = json::parse(client().Get((base + "/frames").c_str())->body);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(frames[1]["dims"], json::array({16, 16, 16}));
    // A frame on another grid, and garbage, are refused; nothing changes.
    expectError(client().Put((base + "/frames/3").c_str(), ballFrame(3, 12), "application/octet-stream"), 400, "invalid_argument");
    expectError(client().Put((base + "/frames/3").c_str(), "not a vdb", "application/octet-stream"), 422, "unsupported_media");
    EXPECT_EQ(json::parse(client().Get((base + "/frames").c_str())->body).size(), 3u);
    expectError(client().Post((base + "/animate").c_str(), "{}", "application/json"), 400, "invalid_argument");  // no painted frame yet

    // Views of frames 0 and 2 with targets: the key frames.
    for (int f : {0, 2}) {
        const json view = {{"camera", {{"eye", {0.3, 0.6, 2.8}}, {"target", {0, 0, 0}}, {"width", 16}, {"height", 16}}}, {"frame", f}};
        auto r = client().Post((base + "/views").c_str(), view.dump(), "application/json");
        ASSERT_EQ(r->status, 201) << r->body;
        EXPECT_EQ(json::parse(r->body)["frame"], f);
        core::Image target(16, 16);
        for (float& x : target.rgba) x = 0.5f;
        const std::string vid = json::parse(r->body)["id"];
        ASSERT_EQ(client().Put((base + "/views/" + vid + "/target").c_str(), pngOf(target), "image/png")->status, 200);
    }
    // The volume's own solve ignores views of frames.
    expectError(client().Post((base + "/solve").c_str(), "{}", "application/json"), 400, "invalid_argument");
    json e = expectError(client().Post((base + "/animate").c_str(), R"({"sweeps": 0, "unknowns": ["extinction"], "fps": -1})", "application/json"),
                         400, "invalid_argument");
    std::set<std::string> paths;
    for (const auto& d : e["error"]["details"]) paths.insert(d["path"].get<std::string>());
    EXPECT_EQ(paths, (std::set<std::string>{"/sweeps", "/unknowns", "/fps"}));

    // The key-frame solve: a job with a progress event per key frame and sweep.
    auto started = client().Post((base + "/animate").c_str(), R"({"sweeps": 2, "max_iterations": 10, "temporal": 0.05})", "application/json");
    ASSERT_EQ(started->status, 202) << started->body;
    const std::string jid = json::parse(started->body)["job"];
    const auto events = readEvents(client(), "/api/v1/jobs/" + jid + "/events");
    EXPECT_EQ(std::count(events.begin(), events.end(), "progress"), 4) << "2 sweeps × 2 key frames";
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back(), "done");
    const json job = json::parse(client().Get(("/api/v1/jobs/" + jid).c_str())->body);
    EXPECT_EQ(job["result"]["key_frames"], json::array({0, 2}));
    EXPECT_EQ(job["result"]["frames"], json::array({0, 1, 2}));
    frames = json::parse(client().Get((base + "/frames").c_str())->body);
    for (const auto& f : frames) EXPECT_TRUE(f["solved"].get<bool>()) << f.dump();

    // Frame 1 (no views) as a VDB: the blend of its key frames, with emission.
    auto vdb = client().Get((base + "/frames/1.vdb").c_str());
    ASSERT_EQ(vdb->status, 200);
    const auto path = m_dir / "frame1.vdb";
    std::ofstream(path, std::ios::binary) << vdb->body;
    const core::Volume one = core::loadVdb(path.string());
    ASSERT_TRUE(one.hasEmission());
    float peak = 0;
    for (float x : one.emission()) peak = std::max(peak, x);
    EXPECT_GT(peak, 0.01f) << "the key frames' emission, blended";

    // Every frame to PNG: a job.
    auto render = client().Post((base + "/frames/render").c_str(),
                                R"({"camera": {"eye": [0.3, 0.6, 2.8], "target": [0, 0, 0], "width": 32, "height": 32}, "exposure": 1})",
                                "application/json");
    ASSERT_EQ(render->status, 202) << render->body;
    const std::string rid = json::parse(render->body)["job"];
    EXPECT_EQ(readEvents(client(), "/api/v1/jobs/" + rid + "/events").back(), "done");
    const json rendered = json::parse(client().Get(("/api/v1/jobs/" + rid).c_str())->body);
    ASSERT_EQ(rendered["result"]["frame_urls"].size(), 3u);
    auto png = client().Get(rendered["result"]["frame_urls"][2].get<std::string>().c_str());
    ASSERT_EQ(png->status, 200);
    EXPECT_EQ(core::loadImageFromMemory(png->body.data(), png->body.size(), "frame").image.width, 32);

    // Frames and views' frames survive a restart; DELETE drops a frame.
    restart();
    frames = json::parse(client().Get((base + "/frames").c_str())->body);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_TRUE(frames[1]["solved"].get<bool>());
    EXPECT_EQ(frames[0]["views"], 1);
    const json session = json::parse(client().Get(base.c_str())->body);
    EXPECT_EQ(session["views"][1]["frame"], 2);
    ASSERT_EQ(client().Delete((base + "/frames/1").c_str())->status, 200);
    EXPECT_EQ(json::parse(client().Get((base + "/frames").c_str())->body).size(), 2u);
    expectError(client().Get((base + "/frames/1.vdb").c_str()), 404, "not_found");
}

TEST_F(AnimationApi, OneVdbHoldingTheWholeAnimationUploadsEveryFrame) {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    auto read = [](const std::string& file) {
        std::ifstream in(std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/animate/" + file, std::ios::binary);
        std::stringstream bytes;
        bytes << in.rdbuf();
        return bytes.str();
    };
    auto r = client().Put((base + "/frames").c_str(), read("ball_all.vdb"), "application/octet-stream");
    ASSERT_EQ(r->status, 200) << r->body;
    const json frames = json::parse(r->body);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(frames[2]["frame"], 2);
    // A file of one frame (no stamped grids) is not an animation; nothing changes.
    expectError(client().Put((base + "/frames").c_str(), read("ball.0.vdb"), "application/octet-stream"), 422, "unsupported_media");
    EXPECT_EQ(json::parse(client().Get((base + "/frames").c_str())->body).size(), 3u);
}

/// Frames 0–2 of the ball uploaded to a new session, frames 0 and 2 painted grey, animated; every
/// frame as downloaded afterwards.
std::vector<core::Volume> AnimationApi::animateTheBall() {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    for (int f = 0; f <= 2; ++f)
        EXPECT_EQ(client().Put((base + "/frames/" + std::to_string(f)).c_str(), ballFrame(f), "application/octet-stream")->status, 200);
    for (int f : {0, 2}) {
        const json view = {{"camera", {{"eye", {0.3, 0.6, 2.8}}, {"target", {0, 0, 0}}, {"width", 16}, {"height", 16}}}, {"frame", f}};
        auto r = client().Post((base + "/views").c_str(), view.dump(), "application/json");
        EXPECT_EQ(r->status, 201) << r->body;
        core::Image target(16, 16);
        for (float& x : target.rgba) x = 0.5f;
        const std::string vid = json::parse(r->body)["id"];
        EXPECT_EQ(client().Put((base + "/views/" + vid + "/target").c_str(), pngOf(target), "image/png")->status, 200);
    }
    auto started = client().Post((base + "/animate").c_str(), R"({"sweeps": 2, "max_iterations": 10, "temporal": 0.05})", "application/json");
    EXPECT_EQ(started->status, 202) << started->body;
    const std::string jid = json::parse(started->body)["job"];
    EXPECT_EQ(readEvents(client(), "/api/v1/jobs/" + jid + "/events").back(), "done");
    for (const auto& f : json::parse(client().Get((base + "/frames").c_str())->body)) m_storage.push_back(f["storage"]);
    std::vector<core::Volume> frames;
    for (int f = 0; f <= 2; ++f) {
        auto vdb = client().Get((base + "/frames/" + std::to_string(f) + ".vdb").c_str());
        EXPECT_EQ(vdb->status, 200);
        const auto path = std::filesystem::temp_directory_path() / ("volstyle-frame-" + std::to_string(::getpid()) + ".vdb");
        std::ofstream(path, std::ios::binary) << vdb->body;
        frames.push_back(core::loadVdb(path.string()));
        std::filesystem::remove(path);
    }
    return frames;
}

TEST_F(AnimationApi, SparseFramesAreSolvedAsDenseOnes) {
    // The same animation with every volume stored as bricks (issue #39): each frame, key frame or
    // blended, holds the emission the dense animation gives, voxel for voxel.
    const std::vector<core::Volume> dense = animateTheBall();
    Api::TearDown();
    server::ServerOptions opt;
    opt.volumeLimits.storage = core::VolumeStorage::Sparse;
    start(opt, m_dir.string());
    m_storage.clear();
    const std::vector<core::Volume> sparse = animateTheBall();
    ASSERT_EQ(sparse.size(), 3u);
    EXPECT_EQ(m_storage, std::vector<std::string>(3, "sparse"));
    for (int f = 0; f <= 2; ++f) {
        ASSERT_TRUE(dense[size_t(f)].hasEmission() && sparse[size_t(f)].hasEmission()) << f;
        double worst = 0, peak = 0;
        forEachActiveVoxel(dense[size_t(f)], [&](Int3 p, size_t d) {
            const size_t s = sparse[size_t(f)].index(p.x, p.y, p.z);
            peak = std::max(peak, double(dense[size_t(f)].emission()[3 * d]));
            worst = std::max(worst, double(std::abs(dense[size_t(f)].emission()[3 * d] - sparse[size_t(f)].emission()[3 * s])));
        });
        std::cout << "[ measured ] frame " << f << ": sparse against dense emission, at most " << worst << " apart (peak " << peak << ")\n";
        EXPECT_GT(peak, 1e-3) << f;
        EXPECT_LE(worst, 1e-4 * std::max(peak, 1.0)) << f;
    }
}

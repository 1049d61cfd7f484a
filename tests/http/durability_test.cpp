// Durability with the real binary: kill -9 during a solve, restart on the same data directory;
// sessions, views, targets, lighting and versions come back, and the job reads failed/interrupted.
#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <set>
#include <thread>

#include "core/image/image_io.h"

using json = nlohmann::json;
namespace fs = std::filesystem;

namespace {

/// `volstyle serve --port 0` as a child process; reads the port it prints.
struct ServerProcess {
    pid_t pid = -1;
    int port = 0;
    explicit ServerProcess(const fs::path& dataDir) {
        int out[2];
        EXPECT_EQ(pipe(out), 0);
        pid = fork();
        if (pid == 0) {
            dup2(out[1], STDOUT_FILENO);
            close(out[0]);
            execl(VOLSTYLE_BINARY, VOLSTYLE_BINARY, "serve", "--port", "0", "--data-dir", dataDir.c_str(), "--web-dir",
                  VOLSTYLE_SOURCE_DIR "/web", static_cast<char*>(nullptr));
            _exit(127);
        }
        close(out[1]);
        FILE* f = fdopen(out[0], "r");
        char line[256] = {};
        if (fgets(line, sizeof line, f)) std::sscanf(line, "volstyle: serving http://127.0.0.1:%d/", &port);
        fclose(f);
        EXPECT_GT(port, 0) << "the server did not print its address: " << line;
    }
    int stop(int sig) {
        kill(pid, sig);
        int status = 0;
        waitpid(pid, &status, 0);
        return status;
    }
};

}  // namespace

TEST(Durability, KillDuringASolveThenRestart) {
    const fs::path dir = fs::temp_directory_path() / "volstyle-durability-test";
    fs::remove_all(dir);
    std::string sid, job;
    {
        ServerProcess server(dir);
        httplib::Client c("127.0.0.1", server.port);
        c.set_read_timeout(120, 0);  // sanitizer builds answer in seconds
        auto r = c.Post("/api/v1/sessions", R"({"scene": "builtin:sphere", "resolution": 24})", "application/json");
        ASSERT_EQ(r->status, 201) << r->body;
        sid = json::parse(r->body)["id"];
        const std::string base = "/api/v1/sessions/" + sid;
        ASSERT_EQ(c.Put((base + "/lighting").c_str(), R"({"sun": {"direction": [0, 1, 0], "irradiance": [5, 5, 5]}, "background": [0.1, 0.1, 0.1]})", "application/json")->status, 200);
        for (int i = 0; i < 2; ++i) {
            r = c.Post((base + "/views").c_str(), R"({"camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 32, "height": 32}})", "application/json");
            ASSERT_EQ(r->status, 201);
            volstyle::core::Image target(32, 32);
            for (float& x : target.rgba) x = 0.6f;
            ASSERT_EQ(c.Put((base + "/views/v" + std::to_string(i + 1) + "/target").c_str(), volstyle::core::encodeImage(target, "png"), "image/png")->status, 200);
        }
        r = c.Post((base + "/solve").c_str(), R"({"max_iterations": 10000, "tolerance": 0, "visible_change": 0})", "application/json");
        ASSERT_EQ(r->status, 202);
        job = json::parse(r->body)["job"];
        for (int i = 0; i < 200; ++i) {
            if (json::parse(c.Get(("/api/v1/jobs/" + job).c_str())->body)["state"] == "running") break;
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(200));  // a few iterations in
        server.stop(SIGKILL);
    }
    ServerProcess server(dir);
    httplib::Client c("127.0.0.1", server.port);
    c.set_read_timeout(120, 0);  // sanitizer builds answer in seconds
    auto r = c.Get(("/api/v1/sessions/" + sid).c_str());
    ASSERT_EQ(r->status, 200) << r->body;
    json s = json::parse(r->body);
    EXPECT_EQ(s["volume"]["version"], 1);
    EXPECT_EQ(s["views"].size(), 2u);
    EXPECT_TRUE(s["views"][1]["has_target"]);
    EXPECT_EQ(s["lighting"]["sun"]["irradiance"], json::array({5.0, 5.0, 5.0}));
    json j = json::parse(c.Get(("/api/v1/jobs/" + job).c_str())->body);
    EXPECT_EQ(j["state"], "failed");
    EXPECT_EQ(j["error"]["code"], "interrupted");
    auto target = c.Get(("/api/v1/sessions/" + sid + "/views/v2/target.png").c_str());
    EXPECT_EQ(target->status, 200);
    // A graceful stop: SIGTERM ends the process with status 0.
    int status = server.stop(SIGTERM);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
    fs::remove_all(dir);
}

namespace {

void truncateFile(const fs::path& p, std::uintmax_t keep) {
    ASSERT_TRUE(fs::exists(p)) << p;
    fs::resize_file(p, std::min(keep, fs::file_size(p) / 2));
}

std::vector<std::string> damagedFiles(const json& session) {
    std::vector<std::string> out;
    for (const auto& d : session["damaged"]) out.push_back(d["file"]);
    return out;
}

}  // namespace

TEST(Durability, ADamagedFileQuarantinesOnlyWhatItHolds) {
    // Before issue #9 a truncated old version or target dropped the whole session (a log line).
    const fs::path dir = fs::temp_directory_path() / "volstyle-damage-test";
    fs::remove_all(dir);
    std::string sid, other;
    {
        ServerProcess server(dir);
        httplib::Client c("127.0.0.1", server.port);
        c.set_read_timeout(120, 0);  // sanitizer builds answer in seconds
        for (std::string* id : {&sid, &other}) {
            auto r = c.Post("/api/v1/sessions", R"({"scene": "builtin:sphere", "resolution": 16})", "application/json");
            ASSERT_EQ(r->status, 201) << r->body;
            *id = json::parse(r->body)["id"];
        }
        const std::string base = "/api/v1/sessions/" + sid;
        for (int i = 0; i < 2; ++i) ASSERT_EQ(c.Post((base + "/revert").c_str(), R"({"version": 1})", "application/json")->status, 200);
        ASSERT_EQ(c.Post((base + "/views").c_str(), R"({"camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 16, "height": 16}})", "application/json")->status, 201);
        volstyle::core::Image target(16, 16);
        for (float& x : target.rgba) x = 0.5f;
        ASSERT_EQ(c.Put((base + "/views/v1/target").c_str(), volstyle::core::encodeImage(target, "png"), "image/png")->status, 200);
        EXPECT_EQ(server.stop(SIGTERM), 0);
    }
    const fs::path sdir = dir / "sessions" / sid;
    truncateFile(sdir / "versions" / "1.vdb", 100);
    truncateFile(sdir / "views" / "v1" / "target.exr", 100);
    {
        fs::resize_file(dir / "sessions" / other / "session.json", 10);  // the other session is unreadable
        ServerProcess server(dir);
        httplib::Client c("127.0.0.1", server.port);
        c.set_read_timeout(120, 0);  // sanitizer builds answer in seconds
        const std::string base = "/api/v1/sessions/" + sid;
        auto r = c.Get(base.c_str());
        ASSERT_EQ(r->status, 200) << "the session survives its damaged files: " << r->body;
        json s = json::parse(r->body);
        EXPECT_EQ(s["volume"]["version"], 3);
        EXPECT_EQ(s["versions"], json::array({1, 2, 3}));
        EXPECT_EQ(damagedFiles(s), (std::vector<std::string>{"versions/1.vdb", "views/v1/target.exr"}));
        EXPECT_FALSE(s["views"][0]["has_target"]) << "the view stays, without its damaged target";
        r = c.Post((base + "/revert").c_str(), R"({"version": 1})", "application/json");
        EXPECT_EQ(r->status, 422) << r->body;
        EXPECT_EQ(json::parse(r->body)["error"]["code"], "io_error");
        EXPECT_EQ(c.Get((base + "/volume.vdb?version=1").c_str())->status, 422);
        EXPECT_EQ(c.Get((base + "/volume.vdb?version=2").c_str())->status, 200);
        EXPECT_EQ(c.Get(("/api/v1/sessions/" + other).c_str())->status, 404);
        json q = json::parse(c.Get("/api/v1/quarantine")->body);
        std::set<std::string> listed;
        for (const auto& e : q) listed.insert(e["session"].get<std::string>() + ":" + e["file"].get<std::string>());
        EXPECT_EQ(listed, (std::set<std::string>{sid + ":versions/1.vdb", sid + ":views/v1/target.exr", other + ":"})) << q.dump();
        EXPECT_TRUE(fs::exists(dir / "quarantine" / other / "session" / "session.json"));
        EXPECT_EQ(server.stop(SIGTERM), 0);
    }
    truncateFile(sdir / "versions" / "3.vdb", 100);  // now the current version
    {
        ServerProcess server(dir);
        httplib::Client c("127.0.0.1", server.port);
        c.set_read_timeout(120, 0);  // sanitizer builds answer in seconds
        auto r = c.Get(("/api/v1/sessions/" + sid).c_str());
        ASSERT_EQ(r->status, 200) << r->body;
        json s = json::parse(r->body);
        EXPECT_EQ(s["volume"]["version"], 2) << "falls back to the newest readable version";
        EXPECT_EQ(damagedFiles(s), (std::vector<std::string>{"versions/1.vdb", "views/v1/target.exr", "versions/3.vdb"}));
        r = c.Post(("/api/v1/sessions/" + sid + "/revert").c_str(), R"({"version": 2})", "application/json");
        ASSERT_EQ(r->status, 200) << r->body;
        EXPECT_EQ(json::parse(r->body)["volume"]["version"], 4) << "numbers go on after the damaged one";
        EXPECT_EQ(server.stop(SIGTERM), 0);
    }
    fs::remove_all(dir);
}

TEST(Durability, TheStylizerSurvivesARestart) {
    // Issue #11: the stylizer's scene, its uploaded meshes and its TF are on disk before the
    // answer, and a restart (kill -9) brings back the same scene rendering the same frame.
    const fs::path dir = fs::temp_directory_path() / "volstyle-durability-stylizer";
    fs::remove_all(dir);
    std::string base, sceneBefore, meshesBefore, frameBefore, revisionBefore;
    const std::string frameRequest = R"({"format": "exr", "camera": {"eye": [0, 6, 12], "target": [0, 0, 0], "width": 32, "height": 24}})";
    {
        ServerProcess server(dir);
        httplib::Client c("127.0.0.1", server.port);
        c.set_read_timeout(120, 0);
        auto r = c.Post("/api/v1/sessions", R"({"scene": "builtin:sphere", "resolution": 16})", "application/json");
        ASSERT_EQ(r->status, 201) << r->body;
        base = "/api/v1/sessions/" + json::parse(r->body)["id"].get<std::string>() + "/stylizer";
        ASSERT_EQ(c.Put((base + "/occluders/board").c_str(), "v -3 2 -3\nv 3 2 -3\nv 3 2 3\nv -3 2 3\nf 1 2 3\nf 1 3 4\n",
                        "application/octet-stream")->status, 200);
        volstyle::core::Image tf(4, 2);
        for (size_t i = 0; i < tf.pixelCount(); ++i) tf.rgba[4 * i] = 1, tf.rgba[4 * i + 1] = 0.5f, tf.rgba[4 * i + 2] = 0.25f, tf.rgba[4 * i + 3] = 1;
        ASSERT_EQ(c.Put((base + "/tf").c_str(), volstyle::core::encodeImage(tf, "exr"), "image/x-exr")->status, 200);
        json scene = json::parse(c.Get(base.c_str())->body);
        scene["occluders"][1]["mesh"] = "board";
        scene["occluders"][1]["manipulation"] = {{"closing", {{"radius_px", 2}}}};
        scene["light"]["shadow_map_size"] = 512;
        // Issue #15: a TF of layers (the uploaded image, a diffusion with an anchored constraint).
        scene["transfer_function"] = {
            {"mode", "multiply"},
            {"depth_range", {0, 30}},
            {"layers", {{{"type", "image"}},
                        {{"type", "diffusion"}, {"blend", "multiply"},
                         {"constraints", {{{"v_bar", 0.3}, {"depth", 0.5}, {"colour", {1, 0, 0}},
                                           {"anchor", {{"position", {0, 0, 0}}, {"follow", "ground"}}}}}}}}}};
        r = c.Put(base.c_str(), scene.dump(), "application/json");
        ASSERT_EQ(r->status, 200) << r->body;
        sceneBefore = c.Get(base.c_str())->body;
        revisionBefore = c.Get(base.c_str())->get_header_value("ETag");
        meshesBefore = c.Get((base + "/occluders").c_str())->body;
        frameBefore = c.Post((base + "/frame").c_str(), frameRequest, "application/json")->body;
        server.stop(SIGKILL);
    }
    ServerProcess server(dir);
    httplib::Client c("127.0.0.1", server.port);
    c.set_read_timeout(120, 0);
    EXPECT_EQ(c.Get(base.c_str())->body, sceneBefore);
    EXPECT_EQ(c.Get(base.c_str())->get_header_value("ETag"), revisionBefore) << "revisions go on, frame URLs are not reused";
    EXPECT_EQ(c.Get((base + "/occluders").c_str())->body, meshesBefore);
    EXPECT_EQ(c.Get((base + "/tf.png").c_str())->status, 200);
    const std::string frameAfter = c.Post((base + "/frame").c_str(), frameRequest, "application/json")->body;
    auto pixels = [](const std::string& exr) { return volstyle::core::loadImageFromMemory(exr.data(), exr.size(), "frame").image.rgba; };
    EXPECT_TRUE(pixels(frameAfter) == pixels(frameBefore)) << "the same frame";  // (the files differ in their date)
    auto undone = c.Post((base + "/undo").c_str(), "", "application/json");
    ASSERT_EQ(undone->status, 200) << "the undo history survives a restart: " << undone->body;
    EXPECT_FALSE(json::parse(undone->body).contains("transfer_function"));
    ASSERT_EQ(c.Post((base + "/redo").c_str(), "", "application/json")->status, 200);
    EXPECT_EQ(json::parse(c.Get(base.c_str())->body), json::parse(sceneBefore));
    server.stop(SIGTERM);

    // A damaged mesh costs its occluder only: the rest of the scene (and the TF) stays.
    const std::string sid = base.substr(std::string("/api/v1/sessions/").size(), 32);
    std::ofstream(dir / "sessions" / sid / "stylizer" / "occluders" / "board.obj", std::ios::binary | std::ios::trunc) << "\x01\x02garbage";
    ServerProcess again(dir);
    httplib::Client c2("127.0.0.1", again.port);
    c2.set_read_timeout(120, 0);
    const json scene = json::parse(c2.Get(base.c_str())->body);
    ASSERT_EQ(scene["occluders"].size(), 1u) << scene;
    EXPECT_EQ(scene["occluders"][0]["mesh"], "builtin:forest/ground");
    EXPECT_TRUE(scene.contains("transfer_function"));
    EXPECT_EQ(scene["light"]["shadow_map_size"], 512);
    const json session = json::parse(c2.Get(("/api/v1/sessions/" + sid).c_str())->body);
    EXPECT_NE(session.dump().find("stylizer/occluders/board.obj"), std::string::npos) << "the damage is listed";
    again.stop(SIGTERM);
    fs::remove_all(dir);
}

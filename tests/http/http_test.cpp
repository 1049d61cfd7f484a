// The HTTP API in-process: every endpoint, error class and flow (fixture in api_fixture.h).
#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <functional>
#include <thread>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/volume/vdb_io.h"
#include "server/http/http_server.h"

#include "api_fixture.h"

using namespace volstyle;
using json = nlohmann::json;
using volstyle::test::Api;
using volstyle::test::addConstantTargetView;
using volstyle::test::pngOf;
using volstyle::test::meanRms;
using volstyle::test::solveToEnd;
using volstyle::test::readEvents;

TEST_F(Api, HealthAndScenes) {
    auto r = client().Get("/api/v1/health");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    json j = json::parse(r->body);
    EXPECT_EQ(j["status"], "ok");
    EXPECT_FALSE(j["gl_renderer"].get<std::string>().empty());
    r = client().Get("/api/v1/scenes");
    EXPECT_EQ(json::parse(r->body).size(), 4u);
}

TEST_F(Api, SessionLifecycle) {
    std::string id = createSession();
    EXPECT_EQ(id.size(), 32u) << "128-bit ids";
    auto r = client().Get(("/api/v1/sessions/" + id).c_str());
    json s = json::parse(r->body);
    EXPECT_EQ(s["volume"]["dims"], json::array({16, 16, 16}));
    EXPECT_EQ(s["volume"]["version"], 1);
    EXPECT_EQ(json::parse(client().Get("/api/v1/sessions")->body).size(), 1u);
    EXPECT_EQ(client().Delete(("/api/v1/sessions/" + id).c_str())->status, 204);
    expectError(client().Get(("/api/v1/sessions/" + id).c_str()), 404, "not_found");
}

TEST_F(Api, RendersPngAndExr) {
    std::string id = createSession();
    json body = {{"camera", {{"eye", {0, 0, 3}}, {"target", {0, 0, 0}}, {"width", 40}, {"height", 30}}}};
    auto r = client().Post(("/api/v1/sessions/" + id + "/render").c_str(), body.dump(), "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
    auto png = core::loadImageFromMemory(r->body.data(), r->body.size(), "render");
    EXPECT_EQ(png.image.width, 40);
    EXPECT_EQ(png.image.height, 30);
    // JPEG for previews (the page's viewport, issue #40): the PNG's picture to the codec's error.
    body["format"] = "jpeg";
    auto jr = client().Post(("/api/v1/sessions/" + id + "/render").c_str(), body.dump(), "application/json");
    ASSERT_EQ(jr->status, 200) << jr->body;
    EXPECT_EQ(jr->get_header_value("Content-Type"), "image/jpeg");
    const core::Image jpeg = core::loadImageFromMemory(jr->body.data(), jr->body.size(), "jpeg").image;
    ASSERT_EQ(jpeg.pixelCount(), png.image.pixelCount());
    double sum = 0;
    for (size_t i = 0; i < jpeg.pixelCount(); ++i)
        for (size_t c = 0; c < 3; ++c)
            sum += 255.0 * std::abs(core::linearToSrgb(jpeg.rgba[4 * i + c]) - core::linearToSrgb(png.image.rgba[4 * i + c]));
    EXPECT_LE(sum / double(3 * jpeg.pixelCount()), 2.0) << "mean levels of 255 (a smooth cloud: JPEG's error is small)";
    body["format"] = "gif";
    expectError(client().Post(("/api/v1/sessions/" + id + "/render").c_str(), body.dump(), "application/json"), 400, "invalid_argument");
    body["format"] = "exr";
    r = client().Post(("/api/v1/sessions/" + id + "/render").c_str(), body.dump(), "application/json");
    auto exr = core::loadImageFromMemory(r->body.data(), r->body.size(), "render");
    EXPECT_GT(exr.image.pixel(20, 15)[3], 0.5f) << "alpha: the sphere covers the centre";
    // "exr_type": "float" (issue #34): the same layers in 32-bit floats, about twice the bytes.
    body["exr_type"] = "float";
    auto full = client().Post(("/api/v1/sessions/" + id + "/render").c_str(), body.dump(), "application/json");
    ASSERT_EQ(full->status, 200) << full->body;
    EXPECT_GT(full->body.size(), r->body.size() * 3 / 2);
    EXPECT_TRUE(core::loadImageFromMemory(full->body.data(), full->body.size(), "render").isRender());
    body["exr_type"] = "double";
    expectError(client().Post(("/api/v1/sessions/" + id + "/render").c_str(), body.dump(), "application/json"), 400, "invalid_argument");
}

TEST_F(Api, LightingRoundTripAndValidation) {
    std::string id = createSession();
    json l = {{"sun", {{"direction", {0, 1, 0}}, {"irradiance", {2, 2, 2}}}}, {"background", {0, 0, 0}}};
    auto r = client().Put(("/api/v1/sessions/" + id + "/lighting").c_str(), l.dump(), "application/json");
    EXPECT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(json::parse(client().Get(("/api/v1/sessions/" + id + "/lighting").c_str())->body)["sun"]["irradiance"], json::array({2.0, 2.0, 2.0}));
    json bad = {{"sun", {{"direction", {0, 1, 0}}, {"irradiance", {-1, 2, 2}}}}, {"phase", {{"type", "rayleigh"}}}};
    json e = expectError(client().Put(("/api/v1/sessions/" + id + "/lighting").c_str(), bad.dump(), "application/json"), 400, "invalid_argument");
    ASSERT_EQ(e["error"]["details"].size(), 2u);  // every problem at once: the type and the value
    EXPECT_EQ(e["error"]["details"][0]["path"], "/phase/type");
    EXPECT_EQ(e["error"]["details"][1]["path"], "/sun/irradiance");
}

TEST_F(Api, EveryErrorClassAnswersTheErrorBody) {
    std::string id = createSession();
    const std::string render = "/api/v1/sessions/" + id + "/render";
    expectError(client().Post(render.c_str(), "{not json", "application/json"), 400, "invalid_json");
    json e = expectError(client().Post("/api/v1/sessions", R"({"scene":"builtin:cloud","colour":1})", "application/json"), 400, "unknown_field");
    EXPECT_EQ(e["error"]["details"][0]["path"], "/colour");
    e = expectError(client().Post("/api/v1/sessions", R"({"resolution":"big"})", "application/json"), 400, "invalid_argument");
    EXPECT_EQ(e["error"]["details"][0]["path"], "/resolution");
    e = expectError(client().Post(render.c_str(), R"({"camera":{"eye":[0,0,3],"target":[0,0,0],"fov_y_deg":190}})", "application/json"), 400, "invalid_argument");
    EXPECT_EQ(e["error"]["details"][0]["path"], "/camera/fov_y_deg");
    expectError(client().Post("/api/v1/sessions", R"({"scene":"/etc/passwd"})", "application/json"), 400, "invalid_argument");
    expectError(client().Post("/api/v1/sessions", json{{"scene", std::string(5000, 'x')}}.dump(), "application/json"), 413, "too_large");
    expectError(client().Get("/api/v1/sessions/0123456789abcdef0123456789abcdef"), 404, "not_found");
    expectError(client().Get("/api/v1/nothing-here"), 404, "not_found");
}

TEST_F(Api, StaticFilesStayInsideTheWebDirectory) {
    auto r = client().Get("/");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    EXPECT_NE(r->body.find("volstyle"), std::string::npos);
    r = client().Get("/../CMakeLists.txt");
    EXPECT_NE(r->status, 200);
    r = client().Get("/%2e%2e/CMakeLists.txt");
    EXPECT_NE(r->status, 200);
}

TEST(ApiSecurity, OtherHostsNeedAToken) {
    server::ServerOptions opt;
    opt.host = "0.0.0.0";
    EXPECT_THROW(server::HttpServer{opt}, InvalidArgument);
}

class ApiWithToken : public Api {
protected:
    void SetUp() override {
        server::ServerOptions opt;
        opt.token = "s3cret-token";
        start(opt);
    }
};

TEST_F(ApiWithToken, MissingOrWrongTokenIs401) {
    expectError(client().Get("/api/v1/scenes"), 401, "unauthorized");
    httplib::Headers wrong = {{"Authorization", "Bearer s3cret-tokeX"}};
    expectError(client().Get("/api/v1/scenes", wrong), 401, "unauthorized");
    httplib::Headers right = {{"Authorization", "Bearer s3cret-token"}};
    EXPECT_EQ(client().Get("/api/v1/scenes", right)->status, 200);
}


TEST_F(Api, PaintingFlowEndToEnd) {
    // Create from a built-in, add two views, upload painted targets (the session's own renders,
    // tinted warm where the volume is), solve, read the events to `done`: renders move toward the
    // targets, and the volume has a new version.
    std::string id = createSession(24);
    const std::string base = "/api/v1/sessions/" + id;
    std::vector<std::string> views;
    for (json eye : {json{0, 0.2, 3}, json{3, 0.4, 0.5}}) {
        auto r = client().Post((base + "/views").c_str(), json{{"camera", {{"eye", eye}, {"target", {0, 0, 0}}, {"width", 24}, {"height", 24}}}}.dump(), "application/json");
        ASSERT_EQ(r->status, 201) << r->body;
        views.push_back(json::parse(r->body)["id"]);
    }
    std::vector<core::Image> targets;
    for (const auto& v : views) {
        auto r = client().Get((base + "/views/" + v + "/render.exr").c_str());
        ASSERT_EQ(r->status, 200);
        core::Image img = core::loadImageFromMemory(r->body.data(), r->body.size(), "render").image;
        for (size_t i = 0; i < img.pixelCount(); ++i) {
            float a = img.rgba[4 * i + 3];
            img.rgba[4 * i] = std::min(1.0f, img.rgba[4 * i] + 0.4f * a);  // paint it warmer
            img.rgba[4 * i + 3] = 1;
        }
        auto put = client().Put((base + "/views/" + v + "/target").c_str(), pngOf(img), "image/png");
        ASSERT_EQ(put->status, 200) << put->body;
        EXPECT_TRUE(json::parse(put->body)["has_target"]);
        targets.push_back(core::loadImageFromMemory(pngOf(img).data(), pngOf(img).size(), "t").image);
    }
    auto before = client().Get((base + "/views/" + views[0] + "/render.exr").c_str());
    auto r = client().Post((base + "/solve").c_str(), R"({"unknowns": ["emission"], "max_iterations": 8})", "application/json");
    ASSERT_EQ(r->status, 202) << r->body;
    std::string job = json::parse(r->body)["job"];
    auto events = readEvents(client(), "/api/v1/jobs/" + job + "/events");
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back(), "done");
    EXPECT_NE(std::find(events.begin(), events.end(), "progress"), events.end());
    EXPECT_NE(std::find(events.begin(), events.end(), "preview"), events.end());
    json status = json::parse(client().Get(("/api/v1/jobs/" + job).c_str())->body);
    EXPECT_EQ(status["state"], "done");
    EXPECT_EQ(status["result"]["version"], 2);
    auto after = client().Get((base + "/views/" + views[0] + "/render.exr").c_str());
    auto rmsTo = [&](const std::string& bytes, const core::Image& t) {
        core::Image img = core::loadImageFromMemory(bytes.data(), bytes.size(), "r").image;
        double s = 0;
        for (size_t i = 0; i < img.pixelCount(); ++i)
            for (int c = 0; c < 3; ++c) s += std::pow(img.rgba[4 * i + size_t(c)] - t.rgba[4 * i + size_t(c)], 2);
        return std::sqrt(s / double(3 * img.pixelCount()));
    };
    double e0 = rmsTo(before->body, targets[0]), e1 = rmsTo(after->body, targets[0]);
    std::cout << "[ measured ] view RMS to its target: " << e0 << " -> " << e1 << "\n";
    EXPECT_LT(e1, 0.5 * e0);
    // Undo: version 1 comes back as version 3; both downloadable.
    r = client().Post((base + "/revert").c_str(), R"({"version": 1})", "application/json");
    EXPECT_EQ(json::parse(r->body)["volume"]["version"], 3);
    auto vdb = client().Get((base + "/volume.vdb?version=2").c_str());
    EXPECT_EQ(vdb->status, 200);
    EXPECT_GT(vdb->body.size(), 1000u);
}

TEST_F(Api, ASolveAfterAStrokeMovesOnlyWhatTheStrokeSees) {
    // Paint, solve, paint a few more pixels of one view, solve again: the second solve starts from
    // the first one's volume, so it is a re-solve after a stroke (SolveOptions::localResolve) and
    // says so in its report; "local_resolve": false solves everything again.
    std::string id = createSession(24);
    const std::string base = "/api/v1/sessions/" + id;
    core::Image target(24, 24);
    for (size_t i = 0; i < target.pixelCount(); ++i)
        for (int c = 0; c < 4; ++c) target.rgba[4 * i + size_t(c)] = c < 3 ? 0.3f : 1.0f;
    json camera = {{"camera", {{"eye", {0, 0.2, 3}}, {"target", {0, 0, 0}}, {"width", 24}, {"height", 24}}}};
    const std::string vid = json::parse(client().Post((base + "/views").c_str(), camera.dump(), "application/json")->body)["id"];
    auto solve = [&](const std::string& body) {
        auto r = client().Post((base + "/solve").c_str(), body, "application/json");
        EXPECT_EQ(r->status, 202) << r->body;
        const std::string job = json::parse(r->body)["job"];
        EXPECT_EQ(readEvents(client(), "/api/v1/jobs/" + job + "/events").back(), "done");
        return json::parse(client().Get(("/api/v1/jobs/" + job).c_str())->body)["result"]["report"];
    };
    ASSERT_EQ(client().Put((base + "/views/" + vid + "/target").c_str(), pngOf(target), "image/png")->status, 200);
    EXPECT_TRUE(solve(R"({"max_iterations": 6})")["local"].is_null());
    for (int y = 10; y < 13; ++y)
        for (int x = 10; x < 13; ++x) target.pixel(x, y)[0] = 0.8f;  // a stroke of 9 pixels
    ASSERT_EQ(client().Put((base + "/views/" + vid + "/target").c_str(), pngOf(target), "image/png")->status, 200);
    const json local = solve(R"({"max_iterations": 6})");
    ASSERT_TRUE(local["local"].is_object()) << local.dump();
    EXPECT_EQ(local["local"]["changed_pixels"], 9);
    EXPECT_LT(local["local"]["unknowns"].get<int>(), local["hull_unknowns"].get<int>());
    for (int y = 4; y < 6; ++y) target.pixel(4, y)[1] = 0.9f;
    ASSERT_EQ(client().Put((base + "/views/" + vid + "/target").c_str(), pngOf(target), "image/png")->status, 200);
    EXPECT_TRUE(solve(R"({"max_iterations": 6, "local_resolve": false})")["local"].is_null());
    expectError(client().Post((base + "/solve").c_str(), R"({"local_resolve": 1})", "application/json"), 400, "invalid_argument");
}

TEST_F(Api, CancellingASolveLeavesTheVolumeAlone) {
    std::string id = createSession(24);
    const std::string base = "/api/v1/sessions/" + id;
    addConstantTargetView(client(), base, 32, 0.8f);
    auto r = client().Post((base + "/solve").c_str(), R"({"max_iterations": 500, "tolerance": 0, "visible_change": 0})", "application/json");
    std::string job = json::parse(r->body)["job"];
    // While it runs, /health answers quickly (p99 of 50 probes under 100 ms).
    std::vector<double> ms;
    for (int i = 0; i < 50; ++i) {
        auto t0 = std::chrono::steady_clock::now();
        EXPECT_EQ(client().Get("/api/v1/health")->status, 200);
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    std::cout << "[ measured ] /health during a solve: p50 " << ms[25] << " ms, p99 " << ms[49] << " ms\n";
    EXPECT_LT(ms[49], 100.0);
    EXPECT_EQ(client().Delete(("/api/v1/jobs/" + job).c_str())->status, 202);
    auto events = readEvents(client(), "/api/v1/jobs/" + job + "/events");
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back(), "cancelled");
    EXPECT_EQ(json::parse(client().Get(base.c_str())->body)["volume"]["version"], 1);
}

TEST_F(Api, UploadErrors) {
    std::string id = createSession();
    const std::string base = "/api/v1/sessions/" + id;
    auto v = client().Post((base + "/views").c_str(), R"({"camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 8, "height": 8}})", "application/json");
    std::string vid = json::parse(v->body)["id"];
    expectError(client().Put((base + "/views/" + vid + "/target").c_str(), "not an image", "image/png"), 422, "unsupported_media");
    expectError(client().Put((base + "/views/" + vid + "/target").c_str(), pngOf(core::Image(9, 8)), "image/png"), 400, "invalid_argument");
    expectError(client().Put((base + "/volume").c_str(), std::string(2000, 'v'), "application/octet-stream"), 422, "unsupported_media");
    expectError(client().Post((base + "/solve").c_str(), "{}", "application/json"), 400, "invalid_argument");  // no target yet
    expectError(client().Get((base + "/views/v99").c_str()), 404, "not_found");
    // Limits: over the upload size is 413; an image over the side limit or a VDB over the voxel
    // limit is refused with the limit named.
    expectError(client().Put((base + "/views/" + vid + "/target").c_str(), std::string(70 * 1024, 'x'), "image/png"), 413, "too_large");
    json big = expectError(client().Put((base + "/views/" + vid + "/target").c_str(), pngOf(core::Image(65, 8)), "image/png"), 422, "unsupported_media");
    EXPECT_NE(big["error"]["message"].get<std::string>().find("[1, 64]"), std::string::npos) << big;
    expectError(client().Get("/api/v1/jobs/0123456789abcdef0123456789abcdef"), 404, "not_found");
}

TEST_F(Api, ConcurrentRendersDuringASolveAllSucceed) {
    std::string id = createSession(24);
    const std::string base = "/api/v1/sessions/" + id;
    addConstantTargetView(client(), base, 24, 0.7f);
    auto r = client().Post((base + "/solve").c_str(), R"({"max_iterations": 40, "tolerance": 0, "visible_change": 0})", "application/json");
    std::string job = json::parse(r->body)["job"];
    // 8 clients, 3 renders each, while the solve runs: renders are served between iterations.
    std::atomic<int> ok{0}, failed{0};
    std::vector<std::thread> clients;
    for (int c = 0; c < 8; ++c)
        clients.emplace_back([&, c] {
            httplib::Client cl("127.0.0.1", m_port);
            cl.set_read_timeout(60, 0);
            for (int i = 0; i < 3; ++i) {
                json body = {{"camera", {{"eye", {3 * std::sin(c + i), 0.5, 3 * std::cos(c + i)}}, {"target", {0, 0, 0}}, {"width", 32}, {"height", 32}}}};
                auto res = cl.Post((base + "/render").c_str(), body.dump(), "application/json");
                (res && res->status == 200 ? ok : failed)++;
            }
        });
    for (auto& t : clients) t.join();
    EXPECT_EQ(ok.load(), 24);
    EXPECT_EQ(failed.load(), 0);
    client().Delete(("/api/v1/jobs/" + job).c_str());
    readEvents(client(), "/api/v1/jobs/" + job + "/events");
}

TEST_F(Api, ViewEndpointsAndSchema) {
    std::string id = createSession();
    const std::string base = "/api/v1/sessions/" + id;
    for (int i = 0; i < 2; ++i)
        ASSERT_EQ(client().Post((base + "/views").c_str(), R"({"camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 8, "height": 8}})", "application/json")->status, 201);
    EXPECT_EQ(json::parse(client().Get((base + "/views").c_str())->body).size(), 2u);
    EXPECT_EQ(json::parse(client().Get((base + "/views/v2").c_str())->body)["camera"]["width"], 8);
    expectError(client().Get((base + "/views/v1/target.png").c_str()), 404, "not_found");  // none yet
    core::Image weights(8, 8);
    for (float& x : weights.rgba) x = 0.5f;
    auto r = client().Put((base + "/views/v1/weights").c_str(), pngOf(weights), "image/png");
    EXPECT_TRUE(json::parse(r->body)["has_weights"]);
    core::Image target(8, 8);
    for (float& x : target.rgba) x = 0.25f;
    client().Put((base + "/views/v1/target").c_str(), pngOf(target), "image/png");
    auto png = client().Get((base + "/views/v1/target.png").c_str());
    EXPECT_EQ(png->status, 200);
    EXPECT_NEAR(core::loadImageFromMemory(png->body.data(), png->body.size(), "t").image.rgba[0], 0.25f, 0.01f);
    EXPECT_EQ(client().Delete((base + "/views/v2").c_str())->status, 204);
    EXPECT_EQ(json::parse(client().Get(base.c_str())->body)["views"].size(), 1u);
    auto schema = client().Get("/api/v1/schema.json");
    EXPECT_EQ(schema->status, 200);
    EXPECT_TRUE(json::parse(schema->body)["definitions"].contains("session"));
}

namespace {

/// Lighting of three suns (light-depth volumes: three per volume on the GL thread's cache).
json threeSuns(double turn) {
    json lights = json::array();
    for (int i = 0; i < 3; ++i) {
        double a = turn + 2.1 * i;
        lights.push_back({{"direction", {std::cos(a), 0.6, std::sin(a)}}, {"irradiance", {1.5 - 0.4 * i, 1.2, 1.0}}});
    }
    return {{"lights", lights}, {"background", {0.05, 0.05, 0.08}}};
}

/// A 24³ cloud under three suns with two painted views, ready for an albedo solve.
std::string albedoSession(httplib::Client& c) {
    auto r = c.Post("/api/v1/sessions", R"({"scene": "builtin:cloud", "resolution": 24})", "application/json");
    const std::string base = "/api/v1/sessions/" + json::parse(r->body)["id"].get<std::string>();
    EXPECT_EQ(c.Put((base + "/lighting").c_str(), threeSuns(0.3).dump(), "application/json")->status, 200);
    addConstantTargetView(c, base, 32, 0.06f);  // darker than the cloud renders: the albedo must fall
    json side = {{"camera", {{"eye", {2.8, 0.4, 1.0}}, {"target", {0, 0, 0}}, {"width", 32}, {"height", 32}}}};
    std::string vid = json::parse(c.Post((base + "/views").c_str(), side.dump(), "application/json")->body)["id"];
    core::Image target(32, 32);
    for (size_t i = 0; i < target.pixelCount(); ++i) target.rgba[4 * i] = 0.09f, target.rgba[4 * i + 1] = 0.06f, target.rgba[4 * i + 2] = 0.04f, target.rgba[4 * i + 3] = 1;
    EXPECT_EQ(c.Put((base + "/views/" + vid + "/target").c_str(), pngOf(target), "image/png")->status, 200);
    return base;
}

/// Solves the session's albedo, returns the solved version's albedo grid (from its VDB).
std::vector<float> solveAlbedo(httplib::Client& c, const std::string& base, const std::function<void(const std::string&)>& during = {}) {
    auto r = c.Post((base + "/solve").c_str(), R"({"unknowns": ["albedo"], "max_iterations": 40, "tolerance": 0, "visible_change": 0})", "application/json");
    EXPECT_EQ(r->status, 202) << r->body;
    const std::string job = json::parse(r->body)["job"];
    if (during) during(job);
    auto events = readEvents(c, "/api/v1/jobs/" + job + "/events");
    EXPECT_EQ(events.back(), "done");
    json report = json::parse(c.Get(("/api/v1/jobs/" + job).c_str())->body)["result"]["report"];
    EXPECT_GE(report["iterations"].get<int>(), 20) << report;
    std::cout << "[ measured ] albedo solve: " << report["iterations"] << " iterations, stopped by " << report["stop_reason"]
              << ", objective " << report["final_objective"] << "\n";
    auto vdb = c.Get((base + "/volume.vdb").c_str());
    const std::string path = testing::TempDir() + "/solved-" + job + ".vdb";
    std::ofstream(path, std::ios::binary) << vdb->body;
    return core::loadVdb(path).albedo();
}

}  // namespace

TEST_F(Api, PreviewsAndOtherSessionsDuringASolveChangeNothing) {
    // Issue #8: a solve's light-depth volumes were freed by the GL thread's cache when other
    // sessions rendered or previews were fetched, and the solve went on binding the dead names.
    const std::vector<float> alone = solveAlbedo(client(), albedoSession(client()));

    const std::string busy = albedoSession(client());
    auto other = client().Post("/api/v1/sessions", R"({"scene": "builtin:plume", "resolution": 16})", "application/json");
    const std::string otherBase = "/api/v1/sessions/" + json::parse(other->body)["id"].get<std::string>();
    ASSERT_EQ(client().Put((otherBase + "/lighting").c_str(), threeSuns(1.7).dump(), "application/json")->status, 200);
    std::atomic<int> otherRenders{0}, previews{0};
    const std::vector<float> disturbed = solveAlbedo(client(), busy, [&](const std::string& job) {
        // Until the job ends: another user renders their session, and this one fetches previews.
        auto running = [&](httplib::Client& c) {
            auto r = c.Get(("/api/v1/jobs/" + job).c_str());
            return r && json::parse(r->body)["state"] != "done" && json::parse(r->body)["state"] != "failed";
        };
        std::thread renderer([&] {
            httplib::Client c("127.0.0.1", m_port);
            for (int i = 0; running(c); ++i) {
                json body = {{"camera", {{"eye", {3 * std::sin(i), 0.3, 3 * std::cos(i)}}, {"target", {0, 0, 0}}, {"width", 12}, {"height", 12}}}};
                if (c.Post((otherBase + "/render").c_str(), body.dump(), "application/json")->status == 200) otherRenders++;
            }
        });
        httplib::Client c("127.0.0.1", m_port);
        while (running(c))
            if (c.Get(("/api/v1/jobs/" + job + "/preview/v1.png").c_str())->status == 200) previews++;
        renderer.join();
    });
    ASSERT_EQ(alone.size(), disturbed.size());
    double diff = 0;
    for (size_t i = 0; i < alone.size(); ++i) diff = std::max(diff, double(std::abs(alone[i] - disturbed[i])));
    std::cout << "[ measured ] albedo difference with " << otherRenders << " renders of another session and " << previews
              << " previews during the solve: " << diff << "\n";
    EXPECT_GT(otherRenders + previews, 2) << "the solve should have been disturbed";
    // Wᵀ sums with float atomics, whose order varies from run to run: the two solves' objectives
    // agree to ~1e-12, but a voxel reaching its albedo bound one iteration apart in bounded CGLS
    // moves the result by up to 1.41e-5 (measured: about half the runs since issue #10's light
    // grids, ≤ 9e-7 the rest). Freed or replaced light-depth volumes (the bug) change far more.
    EXPECT_LE(diff, 1e-4);
}

TEST_F(Api, DeletingASessionDuringASolveCancelsItsJob) {
    // The job must not commit into (or write back) a deleted session, and the GPU copies of the
    // session and of the job's previews are freed on the GL thread.
    std::string id = createSession(24);
    const std::string base = "/api/v1/sessions/" + id;
    const std::string vid = addConstantTargetView(client(), base, 24, 0.7f);
    auto r = client().Post((base + "/solve").c_str(), R"({"max_iterations": 500, "tolerance": 0, "visible_change": 0})", "application/json");
    const std::string job = json::parse(r->body)["job"];
    for (int i = 0; i < 100 && json::parse(client().Get(("/api/v1/jobs/" + job).c_str())->body)["state"] != "running"; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    EXPECT_EQ(client().Get(("/api/v1/jobs/" + job + "/preview/" + vid + ".png").c_str())->status, 200);
    EXPECT_EQ(client().Delete(base.c_str())->status, 204);
    auto events = readEvents(client(), "/api/v1/jobs/" + job + "/events");
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back(), "cancelled");
    expectError(client().Get(base.c_str()), 404, "not_found");
    expectError(client().Get(("/api/v1/jobs/" + job + "/preview/" + vid + ".png").c_str()), 404, "not_found");
}

TEST_F(Api, SolvesTheEnvironmentLightingAndServesItsMap) {
    // Targets rendered under 8 lobes; the lighting set to a black environment; a lights solve
    // brings the renders back and the session's lighting holds the solved radiances.
    std::string id = createSession(24);
    const std::string base = "/api/v1/sessions/" + id;
    expectError(client().Get((base + "/lighting/environment.exr").c_str()), 404, "not_found");  // no environment yet
    json radiance = json::array(), black = json::array();
    for (int i = 0; i < 8; ++i) radiance.push_back({0.3 + 0.2 * (i % 3), 0.6, 1.2 - 0.1 * i}), black.push_back({0, 0, 0});
    auto lighting = [&](const json& r) {
        return json{{"background", {0, 0, 0}}, {"environment", {{"lobes", 8}, {"radiance", r}, {"light_volume_resolution", 12}}}}.dump();
    };
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), lighting(radiance), "application/json")->status, 200);
    for (json eye : {json{0, 0.3, 3}, json{3, 0.5, 0.5}}) {
        auto r = client().Post((base + "/views").c_str(), json{{"camera", {{"eye", eye}, {"target", {0, 0, 0}}, {"width", 24}, {"height", 24}}}}.dump(), "application/json");
        ASSERT_EQ(r->status, 201) << r->body;
        const std::string vid = json::parse(r->body)["id"];
        auto exr = client().Get((base + "/views/" + vid + "/render.exr").c_str());
        ASSERT_EQ(exr->status, 200);
        ASSERT_EQ(client().Put((base + "/views/" + vid + "/target").c_str(), exr->body, "image/x-exr")->status, 200);
    }
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), lighting(black), "application/json")->status, 200);
    expectError(client().Post((base + "/solve").c_str(), R"({"unknowns": ["lights", "extinction"]})", "application/json"), 400, "invalid_argument");
    expectError(client().Post((base + "/solve").c_str(), R"({"unknowns": ["lights"], "lights": {"lobes": 300}})", "application/json"), 400, "invalid_argument");

    const json result = solveToEnd(client(), base, R"({"unknowns": ["lights"], "max_iterations": 25, "regularization": {"laplacian": 0}})")["result"];
    const json rep = result["report"];
    const auto [before, after] = meanRms(rep);
    std::cout << "[ measured ] lights over HTTP: RMS " << before << " -> " << after << " in " << rep["iterations"] << " iterations\n";
    EXPECT_LT(after, 0.05 * before);
    const json solved = json::parse(client().Get((base + "/lighting").c_str())->body);
    ASSERT_EQ(solved["environment"]["radiance"].size(), 8u);
    EXPECT_EQ(solved["environment"], result["lighting"]["environment"]);
    auto map = client().Get((base + "/lighting/environment.exr").c_str());
    ASSERT_EQ(map->status, 200);
    const core::Image img = core::loadImageFromMemory(map->body.data(), map->body.size(), "environment").image;
    EXPECT_EQ(img.width, 512);
    EXPECT_EQ(img.height, 256);
    EXPECT_EQ(client().Get((base + "/lighting/environment.png").c_str())->status, 200);
}

// A solve reports what it is doing from its first second (issue #37): its event stream names the
// phases — preparing_views before anything else, iterating, analysing_reach once the first
// iteration is out (not before it), writing before done — as progress events with a "phase".
#include <chrono>
#include <set>

#include "api_fixture.h"
#include "core/image/image.h"

namespace volstyle::test {
namespace {

class SolvePhases : public Api {};

/// Every event of a job's stream as (name, data), to its final event.
std::vector<std::pair<std::string, json>> eventsOf(httplib::Client& c, const std::string& job) {
    std::string text;
    auto r = c.Get(("/api/v1/jobs/" + job + "/events").c_str(), [&](const char* data, size_t n) {
        text.append(data, n);
        return true;
    });
    std::vector<std::pair<std::string, json>> out;
    for (size_t at = 0; (at = text.find("event: ", at)) != std::string::npos;) {
        const size_t eol = text.find('\n', at), data = text.find("data: ", eol), end = text.find("\n\n", data);
        out.emplace_back(text.substr(at + 7, eol - at - 7), json::parse(text.substr(data + 6, end - data - 6)));
        at = end;
    }
    return out;
}

TEST_F(SolvePhases, AnEventStreamNamesEachPhaseInTurn) {
    const std::string sid = createSession();
    const std::string base = "/api/v1/sessions/" + sid;
    auto v = client().Post((base + "/views").c_str(), R"({"camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 16, "height": 16}})",
                           "application/json");
    ASSERT_EQ(v->status, 201);
    auto render = client().Get((base + "/views/v1/render.png").c_str());
    ASSERT_EQ(client().Put((base + "/views/v1/target").c_str(), render->body, "image/png")->status, 200);
    auto r = client().Post((base + "/solve").c_str(), R"({"unknowns": ["emission"], "max_iterations": 4})", "application/json");
    ASSERT_EQ(r->status, 202) << r->body;
    const auto events = eventsOf(client(), json::parse(r->body)["job"]);
    ASSERT_GE(events.size(), 4u);
    std::vector<std::string> phases;  // each phase as it begins
    int firstIteration = -1, reach = -1;
    for (size_t k = 0; k < events.size(); ++k) {
        const auto& [name, data] = events[k];
        if (name != "progress") continue;
        const std::string phase = data.at("phase");
        if (phases.empty() || phases.back() != phase) phases.push_back(phase);
        if (phase == "iterating" && firstIteration < 0) firstIteration = int(k);
        if (phase == "analysing_reach") reach = int(k);
    }
    EXPECT_EQ(events.front().first, "progress");
    EXPECT_EQ(events.front().second["phase"], "preparing_views") << "the first event comes before the set-up";
    ASSERT_GE(phases.size(), 4u);
    EXPECT_EQ(phases[0], "preparing_views");
    EXPECT_EQ(phases[1], "iterating");
    EXPECT_EQ(phases[2], "analysing_reach");
    EXPECT_EQ(phases.back(), "writing");
    EXPECT_GT(reach, firstIteration) << "the reach analysis runs after the first iteration";
    EXPECT_EQ(events.back().first, "done");
    EXPECT_TRUE(events.back().second["result"]["report"].contains("reach"));
    // The set-up phase by phase (issue #40): what the wait before the first iteration was made of.
    const json report = events.back().second["result"]["report"];
    double sum = 0;
    std::set<std::string> setup;
    for (const auto& p : report["setup"]) sum += p["ms"].get<double>(), setup.insert(p["phase"].get<std::string>());
    EXPECT_TRUE(setup.count("renders and observations") && setup.count("rows") && setup.count("first residual")) << report["setup"];
    EXPECT_NEAR(sum, report["setup_ms"].get<double>(), 1e-6 * sum + 1e-9);
    EXPECT_GT(sum, 0.0);
}

TEST_F(SolvePhases, ClippedTargetPixelsAreLeftOutAndTheReportSaysSo) {
    // Issue #37: paint over an 8-bit render whose pixels were at 255 — those pixels say nothing
    // of what the volume should show; they get weight 0, and the reach report names them instead
    // of blaming the unknowns. ?clip_aware=false keeps them.
    const std::string sid = createSession();
    const std::string base = "/api/v1/sessions/" + sid;
    ASSERT_EQ(client().Post((base + "/views").c_str(), R"({"camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 16, "height": 16}})",
                            "application/json")->status,
              201);
    core::Image painted(16, 16);  // a picture clipped (white) in its left half, orange paint over the right
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            float* p = painted.pixel(x, y);
            p[0] = x < 8 ? 1.0f : 1.0f, p[1] = x < 8 ? 1.0f : 0.54f, p[2] = x < 8 ? 1.0f : 0.24f, p[3] = 1;  // white | the orange brush
        }
    core::SaveOptions png;
    png.writeAlpha = true;
    const std::string bytes = core::encodeImage(painted, "png", png);
    auto r = client().Put((base + "/views/v1/target").c_str(), bytes, "image/png");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(json::parse(r->body)["clipped_pixels"], 128);
    r = client().Post((base + "/solve").c_str(), R"({"unknowns": ["emission"], "max_iterations": 3})", "application/json");
    ASSERT_EQ(r->status, 202) << r->body;
    const auto events = eventsOf(client(), json::parse(r->body)["job"]);
    ASSERT_EQ(events.back().first, "done");
    const json reach = events.back().second["result"]["report"]["reach"];
    EXPECT_EQ(reach["clipped_pixels"], 128);
    EXPECT_NE(reach["advice"].get<std::string>().find("128 pixels of the targets were left out because the picture under the paint was clipped there"),
              std::string::npos)
        << reach;
    r = client().Put((base + "/views/v1/target?clip_aware=false").c_str(), bytes, "image/png");
    EXPECT_EQ(json::parse(r->body)["clipped_pixels"], 0);
    json e = expectError(client().Put((base + "/views/v1/target?clip_aware=maybe").c_str(), bytes, "image/png"), 400, "invalid_argument");
    EXPECT_EQ(e["error"]["details"][0]["path"], "?clip_aware") << "a bad value is refused by name, not read as the default";
}

class QuietStreams : public Api {
protected:
    void SetUp() override {
        server::ServerOptions opt;
        opt.eventKeepAliveSeconds = 0.2;
        start(opt);
    }
};

TEST_F(QuietStreams, AQuietJobStreamSendsKeepAliveComments) {
    // A solve queued behind another job of its session sends no event for a while: its stream still
    // speaks (a comment line each eventKeepAliveSeconds), so a client's read timeout or a proxy
    // does not close a stream that is only quiet.
    const std::string base = "/api/v1/sessions/" + createSession(24);
    ASSERT_EQ(client().Post((base + "/views").c_str(), R"({"camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 48, "height": 48}})",
                            "application/json")->status,
              201);
    core::Image orange(48, 48);  // far from the render: the solve has work for every iteration
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x) orange.pixel(x, y)[0] = 0.9f, orange.pixel(x, y)[1] = 0.4f, orange.pixel(x, y)[3] = 1;
    ASSERT_EQ(client().Put((base + "/views/v1/target").c_str(), core::encodeImage(orange, "exr"), "image/x-exr")->status, 200);
    std::string jobs[2];  // a long light-shaft sequence holds the session, then a solve waits behind it
    auto r = client().Post((base + "/stylizer/sequence").c_str(), R"({"fps": 24, "start": 0, "end": 100})", "application/json");
    ASSERT_EQ(r->status, 202) << r->body;
    jobs[0] = json::parse(r->body)["job"];
    r = client().Post((base + "/solve").c_str(), R"({"unknowns": ["emission"], "max_iterations": 3})", "application/json");
    ASSERT_EQ(r->status, 202) << r->body;
    jobs[1] = json::parse(r->body)["job"];
    std::string text;  // the second job's stream while the first runs
    const auto t0 = std::chrono::steady_clock::now();
    client().Get(("/api/v1/jobs/" + jobs[1] + "/events").c_str(), [&](const char* data, size_t n) {
        text.append(data, n);
        return std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(1500);
    });
    const json second = json::parse(client().Get(("/api/v1/jobs/" + jobs[1]).c_str())->body);
    for (const std::string& job : jobs) client().Delete(("/api/v1/jobs/" + job).c_str());
    ASSERT_EQ(second["state"], "queued") << "the second solve waited behind the first: " << second.dump().substr(0, 600);
    EXPECT_EQ(text.find("event: "), std::string::npos) << "a queued job has nothing to say yet: " << text.substr(0, 300);
    size_t comments = 0;
    for (size_t at = 0; (at = text.find(": keep-alive\n\n", at)) != std::string::npos; ++at) ++comments;
    EXPECT_GE(comments, 3u) << "1.5 s of a quiet stream at 0.2 s: " << text.substr(0, 300);
}

}  // namespace
}  // namespace volstyle::test

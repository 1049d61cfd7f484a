// Operations (issue #41 item 4): GET /ready says whether the store takes writes and GL is up (503
// with why, when not), and GET /metrics counts requests by method, route template and status,
// times them in a histogram, and reports sessions and jobs by state, in Prometheus' text format.
#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <sstream>

#include <fmt/format.h>

#include "api_fixture.h"
#include "server/http/request_metrics.h"

using namespace volstyle;
using namespace volstyle::test;

namespace {

class Operations : public Api {};
class OperationsOnAFolder : public PersistentApi {};

/// The samples of a Prometheus text exposition, "name{labels}" → value; every line must be a
/// comment (HELP, TYPE) or a sample.
std::map<std::string, double> samples(const std::string& text) {
    std::map<std::string, double> out;
    std::istringstream lines(text);
    const std::regex sample(R"re(([a-z_]+(\{([a-z_]+="([^"\\]|\\.)*",?)*\})?) (\S+))re");
    for (std::string line; std::getline(lines, line);) {
        if (line.rfind("# HELP ", 0) == 0 || line.rfind("# TYPE ", 0) == 0) continue;
        std::smatch m;
        EXPECT_TRUE(std::regex_match(line, m, sample)) << "not a sample: " << line;
        if (!m.empty()) out[m[1]] = m[5] == "+Inf" ? INFINITY : std::stod(m[5]);
    }
    return out;
}

}  // namespace

TEST_F(Operations, ReadyWhenGlIsUpAndTheStoreIsMemory) {
    auto r = client().Get("/api/v1/ready");
    ASSERT_EQ(r->status, 200) << r->body;
    const json j = json::parse(r->body);
    EXPECT_EQ(j["status"], "ready");
    EXPECT_EQ(j["store"], testStore().empty() ? "memory" : testStore()) << "the store, or memory without a data folder";
    EXPECT_FALSE(j["gl_renderer"].get<std::string>().empty());
}

TEST_F(Operations, MetricsCountRequestsByRouteTemplateAndTimeThem) {
    // One connection: a request is counted (after its answer is written) before the next one is
    // read. (The fixture's /health pings came on connections of their own: they are not counted
    // on; /scenes is this test's alone.)
    client().set_keep_alive(true);
    const auto before = samples(client().Get("/api/v1/metrics")->body);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(client().Get("/api/v1/scenes")->status, 200);
    ASSERT_EQ(client().Get("/api/v1/nothing-here")->status, 404);
    const std::string id = createSession(16);
    ASSERT_EQ(client().Get(("/api/v1/sessions/" + id).c_str())->status, 200);
    ASSERT_EQ(client().Get("/api/v1/sessions/0123456789abcdef0123456789abcdef")->status, 404);

    auto r = client().Get("/api/v1/metrics");
    ASSERT_EQ(r->status, 200);
    EXPECT_EQ(r->get_header_value("Content-Type"), "text/plain; version=0.0.4; charset=utf-8");
    auto m = samples(r->body);
    for (const auto& [key, value] : before)
        if (key.rfind("volstyle_http_request", 0) == 0 && key.find("_sum") == std::string::npos) m[key] -= value;
    const auto at = [&](const std::string& key) {
        EXPECT_TRUE(m.count(key)) << "no sample " << key << " in\n" << r->body;
        return m.count(key) ? m.at(key) : -1.0;
    };
    EXPECT_EQ(at(R"(volstyle_http_requests_total{method="GET",route="/api/v1/scenes",status="200"})"), 3);
    EXPECT_EQ(at(R"(volstyle_http_requests_total{method="GET",route="unmatched",status="404"})"), 1);
    EXPECT_EQ(at(R"(volstyle_http_requests_total{method="POST",route="/api/v1/sessions",status="201"})"), 1);
    // One label for every session's id: the route's template.
    EXPECT_EQ(at(R"(volstyle_http_requests_total{method="GET",route="/api/v1/sessions/{}",status="200"})"), 1);
    EXPECT_EQ(at(R"(volstyle_http_requests_total{method="GET",route="/api/v1/sessions/{}",status="404"})"), 1);
    // The histogram: cumulative buckets that end at the count, and a positive sum.
    double previous = 0;
    for (double le : server::RequestMetrics::kBuckets) {
        const double n = at(fmt::format(R"(volstyle_http_request_duration_seconds_bucket{{route="/api/v1/scenes",le="{}"}})", le));
        EXPECT_GE(n, previous) << "le " << le;
        previous = n;
    }
    EXPECT_EQ(at(R"(volstyle_http_request_duration_seconds_bucket{route="/api/v1/scenes",le="+Inf"})"), 3);
    EXPECT_EQ(at(R"(volstyle_http_request_duration_seconds_count{route="/api/v1/scenes"})"), 3);
    EXPECT_GT(at(R"(volstyle_http_request_duration_seconds_sum{route="/api/v1/scenes"})"), 0);
    EXPECT_EQ(at("volstyle_sessions"), 1);
    for (const char* state : {"queued", "running", "done", "failed", "cancelled"})
        EXPECT_EQ(at(fmt::format(R"(volstyle_jobs{{state="{}"}})", state)), 0) << state;
    EXPECT_EQ(at(R"(volstyle_gl_queue{kind="long"})"), 0);
    EXPECT_GT(at("volstyle_memory_charged_bytes"), 0) << "the session's volume is charged";
    // GPU memory: what the driver reports, and whether it does (llvmpipe: it does not).
    std::vector<std::pair<std::string, double>> reported;
    for (const auto& [key, value] : m)
        if (key.rfind("volstyle_gpu_memory_reported{", 0) == 0) reported.emplace_back(key, value);
    ASSERT_EQ(reported.size(), 1u) << r->body;
    if (reported[0].first == R"(volstyle_gpu_memory_reported{source="none"})") {
        EXPECT_EQ(reported[0].second, 0);
        EXPECT_EQ(m.count(R"(volstyle_gpu_memory_bytes{kind="available"})"), 0u) << "no figure the driver did not give";
    } else {
        EXPECT_EQ(reported[0].second, 1);
        const double available = at(R"(volstyle_gpu_memory_bytes{kind="available"})");
        EXPECT_GT(available, 0);
        if (m.count(R"(volstyle_gpu_memory_bytes{kind="total"})")) {
            EXPECT_LE(available, m.at(R"(volstyle_gpu_memory_bytes{kind="total"})"));
        }
    }

    // A finished solve is counted by its state.
    addConstantTargetView(client(), "/api/v1/sessions/" + id, 16, 0.5f);
    solveToEnd(client(), "/api/v1/sessions/" + id, R"({"unknowns": ["emission"], "max_iterations": 2})");
    EXPECT_EQ(samples(client().Get("/api/v1/metrics")->body).at(R"(volstyle_jobs{state="done"})"), 1);
}

TEST_F(OperationsOnAFolder, NotReadyWhenTheDataFolderIsGone) {
    auto r = client().Get("/api/v1/ready");
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(json::parse(r->body)["store"], testStore().empty() ? "folder" : testStore());
    std::filesystem::remove_all(m_dir);
    const json e = expectError(client().Get("/api/v1/ready"), 503, "overloaded");
    EXPECT_NE(e["error"]["message"].get<std::string>().find("takes no writes: the data folder"), std::string::npos) << e.dump();
    EXPECT_EQ(client().Get("/api/v1/ready")->get_header_value("Retry-After"), "5");
    EXPECT_EQ(client().Get("/api/v1/health")->status, 200) << "liveness stays: the process is up";
}

TEST_F(Operations, ViewsAreMadeAheadOfASolveWhileIdleAndOnlyWhatChanged) {
    // Issue #40: while the artist paints, the GL thread makes each view's render and rows as the
    // next solve will need them (server/service/solve_prefetch.cpp), once per view, volume and
    // lighting, and never for a change that does not touch them (a target).
    auto made = [&](const char* what) {
        return samples(client().Get("/api/v1/metrics")->body).at(std::string("volstyle_prefetched_views_total{what=\"") + what + "\"}");
    };
    auto waitFor = [&](double renders, double rows) {
        for (int i = 0; i < 600 && (made("renders") < renders || made("rows") < rows); ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        return std::pair{made("renders"), made("rows")};
    };
    const std::string base = "/api/v1/sessions/" + createSession();
    EXPECT_EQ(made("renders"), 0) << "a session without views has nothing to make ahead";
    const std::string camera = R"({"camera": {"eye": [0, 0.2, 3], "target": [0, 0, 0], "width": 16, "height": 16}})";
    ASSERT_EQ(client().Post((base + "/views").c_str(), camera, "application/json")->status, 201);
    EXPECT_EQ(waitFor(1, 1), std::pair(1.0, 1.0));
    ASSERT_EQ(client().Post((base + "/views").c_str(), R"({"camera": {"eye": [3, 0, 0], "target": [0, 0, 0], "width": 16, "height": 16}})",
                            "application/json")->status,
              201);
    EXPECT_EQ(waitFor(2, 2), std::pair(2.0, 2.0)) << "the new view only";
    auto render = client().Get((base + "/views/v1/render.png").c_str());
    ASSERT_EQ(client().Put((base + "/views/v1/target").c_str(), render->body, "image/png")->status, 200);
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // past the GL thread's quiet moment
    EXPECT_EQ(std::pair(made("renders"), made("rows")), std::pair(2.0, 2.0)) << "a target changes no render and no row";
    ASSERT_EQ(client().Put((base + "/lighting").c_str(), R"({"sun": {"direction": [0.3, 1, 0.2], "irradiance": [2, 2, 2]}})", "application/json")
                  ->status,
              200);
    EXPECT_EQ(waitFor(4, 4), std::pair(4.0, 4.0)) << "new lighting: both views again (emission + albedo rows are lit)";
    EXPECT_EQ(samples(client().Get("/api/v1/metrics")->body).at(R"(volstyle_gl_queue{kind="idle"})"), 0);
    const json job = solveToEnd(client(), base, R"({"unknowns": ["emission", "albedo"], "max_iterations": 2})");
    EXPECT_EQ(job["result"]["report"]["row_cache"]["cached_views"], 1) << job.dump();
    EXPECT_EQ(job["result"]["report"]["row_cache"]["written_views"], 0) << "the solve wrote no rows: it took those written ahead";
}

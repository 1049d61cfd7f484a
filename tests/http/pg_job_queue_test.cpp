// The job queue on PostgreSQL (issue #41 item 2), run only under tests/cluster/with_postgres.sh
// (CTest store_postgresql):
//   - the queue itself: a lease held is never claimed, a lapsed one is claimed by exactly one of
//     several replicas claiming at once (FOR UPDATE SKIP LOCKED), the replica that lost a job can
//     no longer write it, and notifications reach another replica's listener;
//   - two servers on one database: a solve running on one is read, streamed (progress through
//     LISTEN/NOTIFY) and cancelled through the other;
//   - a solve whose replica died (a lapsed row) is run again by a live server from its recorded
//     request, and gives the uninterrupted solve's result; a sequence too, its frames then served
//     by either replica; a job that cannot run again fails `interrupted` saying why;
//   - a stylizer change moves the session record's stamp, so a replica holding the session sees it.
// The cluster test (tests/cluster/cluster_test.py) kills a real replica with kill -9 mid-solve.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <set>
#include <thread>

#include "api_fixture.h"
#include "server/store/file_mirror.h"
#include "server/store/job_queue.h"

using namespace volstyle;
using namespace volstyle::test;
using namespace std::chrono_literals;

namespace {

/// A database of the test's own with the store's schema, and no server.
class JobQueueDb : public Api {
protected:
    void SetUp() override {
        ASSERT_TRUE(std::getenv("VOLSTYLE_TEST_STORE")) << "run under tests/cluster/with_postgres.sh";
        server::openPostgresMirror(testStore());  // applies the migrations
    }
    std::unique_ptr<server::JobQueue> queue(const std::string& replica, std::chrono::milliseconds lease) {
        return server::openPostgresJobQueue(testStore(), replica, lease);
    }
};

/// Two servers on one database, with short leases.
class TwoReplicas : public PersistentApi {
protected:
    void SetUp() override {
        ASSERT_TRUE(std::getenv("VOLSTYLE_TEST_STORE")) << "run under tests/cluster/with_postgres.sh";
        m_dir = std::filesystem::temp_directory_path() / ("volstyle-queue-" + std::to_string(::getpid()));
        std::filesystem::remove_all(m_dir);
        server::ServerOptions opt;
        // Short, but renewed three times a lease: 1 s lapsed twice in a row under a loaded CI
        // (a sequence claimed a fourth time and failed 'interrupted'); nothing here waits out a
        // live replica's lease (dead replicas' rows carry 1 ms leases of their own).
        opt.jobLeaseSeconds = 3;
        start(opt, (m_dir / "a").string());
        opt.host = "127.0.0.1";
        opt.port = 0;
        opt.dataDir = (m_dir / "b").string();
        opt.store = testStore();
        opt.vdbReader = VOLSTYLE_BINARY;
        m_second = std::make_unique<server::HttpServer>(opt);
        m_secondPort = m_second->bind();
        m_secondClient = std::make_unique<httplib::Client>("127.0.0.1", m_secondPort);
        m_secondThread = std::thread([this] { m_second->listen(); });
        m_secondClient->set_read_timeout(120, 0);
    }
    void TearDown() override {
        if (m_second) m_second->stop();
        if (m_secondThread.joinable()) m_secondThread.join();
        m_second.reset();
        PersistentApi::TearDown();
    }
    httplib::Client& second() { return *m_secondClient; }
    json jobVia(httplib::Client& c, const std::string& job) {
        auto r = c.Get(("/api/v1/jobs/" + job).c_str());
        EXPECT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
        return r ? json::parse(r->body) : json();
    }
    json waitFinished(httplib::Client& c, const std::string& job, double seconds = 120) {
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
        json j;
        do {
            j = jobVia(c, job);
            if (j.value("state", "") != "queued" && j.value("state", "") != "running") return j;
            std::this_thread::sleep_for(50ms);
        } while (std::chrono::steady_clock::now() < deadline);
        ADD_FAILURE() << "job " << job << " did not finish: " << j.dump();
        return j;
    }
    std::unique_ptr<server::HttpServer> m_second;
    std::unique_ptr<httplib::Client> m_secondClient;
    std::thread m_secondThread;
    int m_secondPort = 0;
};

/// A session with one painted view, ready to solve.
std::string paintedSession(httplib::Client& c, int resolution = 16, float paint = 0.5f) {
    auto r = c.Post("/api/v1/sessions", json{{"scene", "builtin:sphere"}, {"resolution", resolution}}.dump(), "application/json");
    EXPECT_EQ(r->status, 201) << r->body;
    const std::string id = json::parse(r->body)["id"];
    addConstantTargetView(c, "/api/v1/sessions/" + id, resolution, paint);
    return id;
}

}  // namespace

TEST_F(JobQueueDb, AHeldLeaseIsNeverClaimedAndALapsedOneByExactlyOneReplica) {
    auto a = queue("a", 400ms), b = queue("b", 60s);
    a->add("j1", "s1", "solve", "{}", "running", "{}");
    EXPECT_FALSE(b->claimLapsed()) << "a's lease holds";
    ASSERT_EQ(a->renew({"j1"}).size(), 1u);
    std::this_thread::sleep_for(600ms);  // a stops renewing: as if killed
    const auto claimed = b->claimLapsed();
    ASSERT_TRUE(claimed);
    EXPECT_EQ(claimed->id, "j1");
    EXPECT_EQ(claimed->attempt, 2);
    EXPECT_EQ(claimed->previousOwner, a->owner());
    EXPECT_EQ(claimed->inputs, "{}");
    EXPECT_TRUE(a->renew({"j1"}).empty()) << "a's lease is b's now";
    EXPECT_FALSE(a->write("j1", "done", "{\"from\": \"a\"}")) << "the replica that lost a job cannot write it";
    EXPECT_TRUE(b->write("j1", "done", "{\"from\": \"b\"}"));
    EXPECT_EQ(a->record("j1"), "{\"from\": \"b\"}");
    EXPECT_FALSE(a->claimLapsed()) << "a finished job holds no lease";

    // 24 lapsed jobs, four replicas claiming at once: each job is claimed exactly once.
    auto dead = queue("dead", 1ms);
    for (int i = 0; i < 24; ++i) dead->add("k" + std::to_string(i), "s", "solve", "{}", "queued", "{}");
    std::this_thread::sleep_for(20ms);
    std::mutex mutex;
    std::multiset<std::string> ids;
    std::vector<std::thread> claimers;
    for (int r = 0; r < 4; ++r)
        claimers.emplace_back([&, r] {
            auto q = queue("r" + std::to_string(r), 60s);
            while (auto c = q->claimLapsed()) {
                std::lock_guard lock(mutex);
                ids.insert(c->id);
            }
        });
    for (auto& t : claimers) t.join();
    EXPECT_EQ(ids.size(), 24u);
    EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()).size(), 24u) << "no job claimed twice";
}

TEST_F(JobQueueDb, NotificationsReachAnotherReplica) {
    auto a = queue("a", 60s), b = queue("b", 60s);
    std::vector<std::string> heard;
    const server::JobQueue::Listener on = [&](const std::string& id, const std::string& what, const std::string& data) {
        heard.push_back(id + " " + what + " " + data);
    };
    b->listen(on, 10ms);  // LISTEN before anything is sent
    a->add("j1", "s1", "solve", "{}", "queued", "{}");
    a->publish("j1", "progress", R"({"iteration": 3})");
    a->publish("j1", "preview", std::string(9000, 'x'));  // over NOTIFY's payload limit: "read the record"
    EXPECT_TRUE(a->write("j1", "running", "{}"));
    EXPECT_TRUE(b->requestCancel("j1"));
    for (int i = 0; i < 20 && heard.size() < 4; ++i) b->listen(on, 100ms);
    const std::vector<std::string> expected = {R"(j1 progress {"iteration": 3})", "j1 state ", "j1 state ", "j1 cancel "};
    EXPECT_EQ(heard, expected);
    EXPECT_EQ(a->renew({"j1"}).at(0).cancel, true) << "the cancel is also read at the next renewal";
}

TEST_F(TwoReplicas, ASolveRunningOnOneIsReadStreamedAndCancelledThroughTheOther) {
    const std::string sid = paintedSession(client(), 32, 0.3f);
    // Long enough to be seen running (seconds): no tolerance, many iterations, two unknowns.
    auto r = client().Post(("/api/v1/sessions/" + sid + "/solve").c_str(),
                           R"({"unknowns": ["albedo", "emission"], "max_iterations": 10000, "tolerance": 0, "visible_change": 0})", "application/json");
    ASSERT_EQ(r->status, 202) << r->body;
    const std::string job = json::parse(r->body)["job"];
    // The second replica streams the job's events: progress relayed through NOTIFY, then the end.
    std::vector<std::string> events;
    httplib::Client streamClient("127.0.0.1", m_secondPort);  // a client of its own: one request at a time each
    std::thread stream([&] { events = readEvents(streamClient, "/api/v1/jobs/" + job + "/events"); });
    json seen;
    for (int i = 0; i < 400; ++i) {
        seen = jobVia(second(), job);
        if (seen["state"] == "running" && !seen["progress"].is_null() && seen["progress"].value("iteration", 0) > 0) break;
        std::this_thread::sleep_for(50ms);
    }
    EXPECT_EQ(seen["state"], "running") << seen.dump();
    std::this_thread::sleep_for(300ms);  // some iterations go by on the first replica
    auto del = second().Delete(("/api/v1/jobs/" + job).c_str());
    ASSERT_EQ(del->status, 202) << del->body;
    const json end = waitFinished(second(), job, 30);
    EXPECT_EQ(end["state"], "cancelled") << end.dump().substr(0, 2000);
    EXPECT_EQ(jobVia(client(), job)["state"], "cancelled");
    stream.join();
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back(), "cancelled");
    EXPECT_GE(std::count(events.begin(), events.end(), "progress"), 3) << "progress relayed while it ran";
}

TEST_F(TwoReplicas, ASolveWhoseReplicaDiedRunsAgainFromItsRequestWithTheSameResult) {
    const std::string request = R"({"unknowns": ["emission"], "max_iterations": 12, "tolerance": 0, "visible_change": 0})";
    // The reference: the solve run through, on a session of its own.
    const std::string reference = paintedSession(client());
    const json expected = solveToEnd(client(), "/api/v1/sessions/" + reference, request);
    ASSERT_EQ(expected["state"], "done") << expected.dump();
    // The same solve, started by a replica that died at once: its row names its request, its
    // lease lapsed, and no replica alive holds it.
    const std::string sid = paintedSession(client());
    const std::string job = sid.substr(0, 8) + "0123456789abcdef0123456789abcdef";
    auto dead = server::openPostgresJobQueue(testStore(), "dead", 1ms);
    dead->add(job, sid, "solve", request, "running", R"({"format": 1, "id": ")" + job + R"(", "session": ")" + sid +
                                                         R"(", "state": "running", "progress": {}, "result": null, "error": null})");
    const json end = waitFinished(second(), job);
    ASSERT_EQ(end["state"], "done") << end.dump();
    EXPECT_EQ(end["result"]["version"], 2);
    const json& a = expected["result"]["report"];
    const json& b = end["result"]["report"];
    EXPECT_EQ(a["iterations"], b["iterations"]);
    // Float atomics may order the adjoint's sums differently: equal to 1e-5 of where it started.
    const double start = a["initial_objective"].get<double>();
    EXPECT_NEAR(a["final_objective"].get<double>(), b["final_objective"].get<double>(), 1e-5 * start);
    EXPECT_NEAR(a["final_rms"][0].get<double>(), b["final_rms"][0].get<double>(), 1e-5 * a["initial_rms"][0].get<double>());
    // And the volumes render alike (the views are the sessions' first, v1).
    auto render = [&](const std::string& s) {
        const std::string bytes = client().Get(("/api/v1/sessions/" + s + "/views/v1/render.exr").c_str())->body;
        return core::loadImageFromMemory(bytes.data(), bytes.size(), "render.exr").image;
    };
    const core::Image x = render(reference), y = render(sid);
    ASSERT_EQ(x.rgba.size(), y.rgba.size());
    float peak = 0, worst = 0;
    for (size_t i = 0; i < x.rgba.size(); ++i) peak = std::max(peak, std::abs(x.rgba[i])), worst = std::max(worst, std::abs(x.rgba[i] - y.rgba[i]));
    EXPECT_LE(worst, 1e-4f * peak) << "the re-run's volume renders as the uninterrupted one's";
    const json session = json::parse(client().Get(("/api/v1/sessions/" + sid).c_str())->body);
    EXPECT_EQ(session["volume"]["version"], 2) << "committed once, visible on every replica";
    // Both solves are in the queue's figures on either replica; each replica counts its own.
    const std::string metrics = client().Get("/api/v1/metrics")->body;
    EXPECT_NE(metrics.find("volstyle_job_queue{state=\"done\"} 2\n"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("volstyle_job_queue{state=\"running\"} 0\n"), std::string::npos) << metrics;
}

TEST_F(TwoReplicas, ASequenceWhoseReplicaDiedRendersAgainAndItsFramesComeFromEitherReplica) {
    const std::string sid = paintedSession(client());
    const std::string stylizer = "/api/v1/sessions/" + sid + "/stylizer";
    json scene = json::parse(client().Get(stylizer.c_str())->body);
    scene["camera"]["width"] = 64;
    scene["camera"]["height"] = 36;
    scene["light"]["shadow_map_size"] = 512;
    ASSERT_EQ(client().Put(stylizer.c_str(), scene.dump(), "application/json")->status, 200);
    const std::string job = sid.substr(0, 8) + "fedcba9876543210fedcba9876543210";
    auto dead = server::openPostgresJobQueue(testStore(), "dead", 1ms);
    dead->add(job, sid, "sequence", R"({"fps": 4, "end": 0.5, "video": false})",
              "running", R"({"format": 1, "id": ")" + job + R"(", "session": ")" + sid + R"(", "state": "running", "progress": {}, "result": null, "error": null})");
    const json end = waitFinished(client(), job);
    ASSERT_EQ(end["state"], "done") << end.dump();
    ASSERT_EQ(end["result"]["frames"], 3) << end.dump();
    // The replica that rendered it committed the frames to the store: both replicas send them.
    for (httplib::Client* c : {&client(), &second()}) {
        auto frame = c->Get(end["result"]["frame_urls"][2].get<std::string>().c_str());
        ASSERT_TRUE(frame);
        ASSERT_EQ(frame->status, 200) << frame->body;
        const core::Image last = core::loadImageFromMemory(frame->body.data(), frame->body.size(), "frame").image;
        EXPECT_EQ(last.width, 64);
        EXPECT_EQ(last.height, 36);
    }
}

TEST_F(TwoReplicas, AJobThatCannotRunAgainFailsInterruptedSayingWhy) {
    const std::string sid = paintedSession(client());
    const std::string job = sid.substr(0, 8) + "00000000000000000000000000000001";
    auto dead = server::openPostgresJobQueue(testStore(), "dead", 1ms);
    dead->add(job, sid, "solve", "", "running",  // no request recorded: nothing to run again from
              R"({"format": 1, "id": ")" + job + R"(", "session": ")" + sid + R"(", "state": "running", "progress": {}, "result": null, "error": null})");
    const json end = waitFinished(second(), job);
    EXPECT_EQ(end["state"], "failed") << end.dump();
    EXPECT_EQ(end["error"]["code"], "interrupted") << end.dump();
    EXPECT_NE(end["error"]["message"].get<std::string>().find("start it again"), std::string::npos) << end.dump();
}

TEST_F(TwoReplicas, AStylizerChangeOnOneIsSeenByAnotherThatHeldTheSession) {
    const std::string sid = createSession(16), stylizer = "/api/v1/sessions/" + sid + "/stylizer";
    json scene = json::parse(second().Get(stylizer.c_str())->body);  // the second replica now holds a copy
    scene["camera"]["width"] = 48;  // within the fixture's image limit (64 a side)
    scene["camera"]["height"] = 27;
    scene["light"]["shadow_map_size"] = 512;
    ASSERT_EQ(client().Put(stylizer.c_str(), scene.dump(), "application/json")->status, 200);
    // The scene went with the session's record: its stamp moved, so the second reads it again.
    EXPECT_EQ(json::parse(second().Get(stylizer.c_str())->body)["camera"]["width"], 48);
}

TEST_F(TwoReplicas, AReplicaThatStopsHandsItsJobsBackAndAnotherFinishesThem) {
    const std::string sid = paintedSession(client());
    auto r = client().Post(("/api/v1/sessions/" + sid + "/solve").c_str(), R"({"max_iterations": 40, "tolerance": 0, "visible_change": 0})",
                           "application/json");
    ASSERT_EQ(r->status, 202) << r->body;
    const std::string job = json::parse(r->body)["job"];
    for (int i = 0; i < 400 && jobVia(client(), job)["state"] != "running"; ++i) std::this_thread::sleep_for(10ms);
    // A graceful stop (SIGTERM): the job is handed back, not ended cancelled.
    const auto t0 = std::chrono::steady_clock::now();
    m_server->stop();
    m_thread.join();
    m_server.reset();
    const json end = waitFinished(second(), job);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(end["state"], "done") << end.dump().substr(0, 2000);
    EXPECT_EQ(end["result"]["version"], 2);
    const std::string metrics = second().Get("/api/v1/metrics")->body;
    EXPECT_NE(metrics.find("volstyle_jobs{state=\"done\"} 1\n"), std::string::npos) << "the second replica ran it\n" << metrics;
    std::printf("[ measured ] a stopped replica's solve done on the other %.2f s after the stop began\n", seconds);
}

// GET /sessions through any replica lists every replica's sessions (issue #41), from the summary
// each save writes beside its record: no session is loaded to be listed, a change made through one
// replica shows in the other's list, and a session deleted through one leaves the other's list
// even though the other still holds it.
TEST_F(TwoReplicas, EitherReplicaListsEverySessionWithoutLoadingIt) {
    const auto listed = [](httplib::Client& c) {
        auto r = c.Get("/api/v1/sessions?limit=100");
        EXPECT_EQ(r->status, 200) << r->body;
        std::map<std::string, json> byId;
        for (const json& s : json::parse(r->body)) byId[s["id"]] = s;
        return byId;
    };
    const std::string onA = paintedSession(client()), onB = paintedSession(second());
    for (httplib::Client* c : {&client(), &second()}) {
        const auto all = listed(*c);
        EXPECT_TRUE(all.count(onA) && all.count(onB)) << json(all).dump();
    }
    EXPECT_EQ(listed(client())[onB], json::parse(second().Get(("/api/v1/sessions/" + onB).c_str())->body))
        << "the other replica's session, as it answers for it";
    EXPECT_NE(client().Get("/api/v1/metrics")->body.find("\nvolstyle_sessions 1\n"), std::string::npos) << "A listed B's session without loading it";

    // A change through B shows in A's list; a deletion through B leaves it, though A holds the session.
    ASSERT_EQ(second().Post(("/api/v1/sessions/" + onA + "/views").c_str(), R"({"camera": {"eye": [0, 0, 3], "target": [0, 0, 0]}})",
                            "application/json")->status, 201);
    EXPECT_EQ(listed(client())[onA]["views"].size(), 2u);
    ASSERT_EQ(second().Delete(("/api/v1/sessions/" + onA).c_str())->status, 204);
    EXPECT_EQ(listed(client()).count(onA), 0u);
    EXPECT_EQ(listed(second()).count(onA), 0u);

    // A record saved by a volstyle before summaries (its summary removed from the store): listed
    // through A, which does not hold it, from its record and files, without being loaded; its
    // summary is then in the store for every replica.
    const std::string old = paintedSession(second());
    const std::string sql = "DELETE FROM volstyle_files WHERE path = 'sessions/" + old + "/summary.json'";
    ASSERT_EQ(std::system(("psql -q '" + testStore() + "' -c \"" + sql + "\" > /dev/null").c_str()), 0);
    const auto held = [&] {
        const std::string m = client().Get("/api/v1/metrics")->body;
        const size_t at = m.find("\nvolstyle_sessions ");
        return at == std::string::npos ? -1 : std::stoi(m.substr(at + 19));
    };
    const int before = held();
    const auto viaA = listed(client());
    ASSERT_TRUE(viaA.count(old)) << json(viaA).dump();
    EXPECT_EQ(viaA.at(old), json::parse(second().Get(("/api/v1/sessions/" + old).c_str())->body));
    EXPECT_EQ(held(), before) << "A read it to list it, and did not keep it";
    const std::string count = "SELECT count(*) FROM volstyle_files WHERE path = 'sessions/" + old + "/summary.json'";
    EXPECT_EQ(std::system(("test \"$(psql -tA '" + testStore() + "' -c \"" + count + "\")\" = 1").c_str()), 0) << "the summary was written back";
}

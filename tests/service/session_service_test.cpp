// The session services without GL (issue #36): a FakeGlExecutor stands in for the GL thread, so
// creation, views, versions, the stylizer's scene and undo, jobs, persistence and recovery are
// tested without a GL context, and every test asserts that it needed none.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include "core/image/image_io.h"
#include "core/translucent/perturbation.h"
#include "protocol/job_json.h"
#include "protocol/stylize_json.h"
#include "server/service/services.h"
#include "tests/service/fake_gl_executor.h"

namespace volstyle {
namespace {

namespace fs = std::filesystem;
using protocol::ApiError;
using protocol::ErrorCode;
using server::Session;
using server::Services;

/// A data folder of its own, removed afterwards.
struct TempDir {
    fs::path path;
    TempDir() {
        path = fs::temp_directory_path() / ("volstyle-service-test-" + server::SessionStore::newId());
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

class ServiceTest : public ::testing::Test {
protected:
    std::unique_ptr<Services> makeService(const std::string& dataDir = "") {
        server::ServiceLimits limits;
        limits.maxQueuedJobs = 2;
        return std::make_unique<Services>(limits, dataDir, std::make_unique<test::FakeGlExecutor>(counts));
    }
    static protocol::CreateSessionRequest smallCloud() {
        protocol::CreateSessionRequest r;
        r.scene = "builtin:cloud";
        r.resolution = 16;
        return r;
    }
    static core::Camera smallCamera() {
        core::Camera c;
        c.width = c.height = 8;
        return c;
    }
    static std::string targetPng(float value) {
        core::Image target(8, 8);
        for (float& v : target.rgba) v = value;
        core::SaveOptions exact;
        exact.halfFloat = false;
        return core::encodeImage(target, "exr", exact);
    }
    /// The session's current volume (a copy, under its lock).
    static core::Volume volumeOf(Session& s) {
        std::lock_guard lock(s.mutex);
        return s.volume.current;
    }
    static int versionOf(Session& s) {
        std::lock_guard lock(s.mutex);
        return s.volume.version;
    }
    void TearDown() override { EXPECT_EQ(counts->shortTasks, allowedShortTasks) << "a GL-free operation posted work to the GL thread"; }

    int allowedShortTasks = 0;  ///< a service that queued a job frees GPU objects when it stops
    std::shared_ptr<test::FakeGlExecutor::Counts> counts = std::make_shared<test::FakeGlExecutor::Counts>();
};

core::Perturbation someNoise(uint32_t seed) {
    core::Perturbation p;
    p.propertyAmplitude = 0.5;
    p.seed = seed;
    return p;
}

TEST_F(ServiceTest, CreatesFindsAndRemovesSessions) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    EXPECT_EQ(service->sessions.find(s->id), s);
    EXPECT_EQ(versionOf(*s), 1);
    EXPECT_EQ(volumeOf(*s).dims(), (Int3{16, 16, 16}));
    service->sessions.remove(s->id);
    try {
        service->sessions.find(s->id);
        FAIL() << "a removed session was found";
    } catch (const ApiError& e) {
        EXPECT_EQ(e.code(), ErrorCode::NotFound);
    }
}

TEST_F(ServiceTest, ViewsHoldTheirTargetsUntilRemoved) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    const server::SessionView v = service->sessions.addView(*s, smallCamera());
    EXPECT_EQ(v.id, "v1");
    EXPECT_FALSE(v.target.has_value());
    const server::SessionView withTarget = service->sessions.setViewImage(*s, v.id, server::ViewImage::Target, targetPng(0.5f));
    ASSERT_TRUE(withTarget.target.has_value());
    EXPECT_EQ(withTarget.target->width, 8);
    EXPECT_FALSE(service->sessions.removeViewImage(*s, v.id, server::ViewImage::Target).target.has_value());
    service->sessions.removeView(*s, v.id);
    EXPECT_THROW(service->sessions.view(*s, v.id), ApiError);
    EXPECT_EQ(service->sessions.addView(*s, smallCamera()).id, "v2");  // ids are never reused
}

TEST_F(ServiceTest, EditsAreVersionsAndRevertIsANewVersion) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    const std::vector<float> first = volumeOf(*s).extinction();
    EXPECT_EQ(service->volumes.perturb(*s, someNoise(3)), 2);
    const std::vector<float> edited = volumeOf(*s).extinction();
    EXPECT_NE(edited, first);
    EXPECT_EQ(service->volumes.revert(*s, 1), 3);  // nothing is lost: the edit stays version 2
    EXPECT_EQ(volumeOf(*s).extinction(), first);
    EXPECT_EQ(service->volumes.revert(*s, 2), 4);
    EXPECT_EQ(volumeOf(*s).extinction(), edited);
    try {
        service->volumes.revert(*s, 9);
        FAIL() << "a version that does not exist was reverted to";
    } catch (const ApiError& e) {
        EXPECT_EQ(e.code(), ErrorCode::NotFound);
    }
}

// Issue #36, lost updates: an edit copies the volume, works off the lock, then commits. A change
// committed in between must not be silently overwritten by the stale copy.
TEST_F(ServiceTest, AnEditRacedByAnotherChangeIsRefusedNotLost) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    ASSERT_EQ(service->volumes.perturb(*s, someNoise(1)), 2);
    const std::vector<float> original = [&] {
        service->volumes.revert(*s, 1);  // version 3: the original content
        return volumeOf(*s).extinction();
    }();
    // While edit A (noise 5) works on its copy of version 3, edit B (revert to version 2) commits.
    std::vector<float> committedByB;
    bool raced = false;
    service->volumes.setVolumeEditHook([&] {
        if (raced) return;
        raced = true;
        std::thread other([&] { EXPECT_EQ(service->volumes.revert(*s, 2), 4); });  // another request's thread
        other.join();
        committedByB = volumeOf(*s).extinction();
    });
    try {
        service->volumes.perturb(*s, someNoise(5));
        FAIL() << "the stale edit was committed over version 4";
    } catch (const ApiError& e) {
        EXPECT_EQ(e.code(), ErrorCode::Busy);  // 409
        EXPECT_NE(std::string(e.what()).find("version 3 → 4"), std::string::npos) << e.what();
    }
    EXPECT_EQ(versionOf(*s), 4);
    EXPECT_EQ(volumeOf(*s).extinction(), committedByB);  // B's change stands
    EXPECT_NE(committedByB, original);
    // Sent again, the edit applies to version 4.
    service->volumes.setVolumeEditHook({});
    EXPECT_EQ(service->volumes.perturb(*s, someNoise(5)), 5);
}

// Two edits racing for real, many times. Each edit scales the extinction by its own noise
// factor (1 + a·n(x), no displacement), so the factors commute: the current volume must be the
// first one times the factor of every edit that was acknowledged. A lost update drops a factor.
TEST_F(ServiceTest, ConcurrentEditsNeverLoseAnAcknowledgedOne) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    const core::Volume first = volumeOf(*s);
    std::mutex mutex;
    std::vector<uint32_t> acknowledged;
    std::atomic<int> refused{0};
    auto editor = [&](uint32_t seedBase) {
        for (uint32_t i = 0; i < 8; ++i) try {
                service->volumes.perturb(*s, someNoise(seedBase + i));
                std::lock_guard lock(mutex);
                acknowledged.push_back(seedBase + i);
            } catch (const ApiError& e) {
                EXPECT_EQ(e.code(), ErrorCode::Busy);
                ++refused;
            }
    };
    std::thread a(editor, 10), b(editor, 100);
    a.join(), b.join();
    EXPECT_EQ(int(acknowledged.size()) + refused, 16);
    EXPECT_EQ(versionOf(*s), 1 + int(acknowledged.size()));
    core::Volume expected = first;
    for (uint32_t seed : acknowledged) expected = core::perturbVolume(expected, someNoise(seed));
    const std::vector<float> got = volumeOf(*s).extinction();
    ASSERT_EQ(got.size(), expected.extinction().size());
    double worst = 0;
    for (size_t i = 0; i < got.size(); ++i)
        worst = std::max(worst, std::abs(double(got[i]) - expected.extinction()[i]) / (1e-6 + std::abs(expected.extinction()[i])));
    EXPECT_LT(worst, 1e-4) << acknowledged.size() << " edits acknowledged, " << refused << " refused";
}

TEST_F(ServiceTest, StylizerScenesUndoAndRedo) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    const server::StylizerSnapshot first = service->stylizer.stylizer(*s);
    nlohmann::json j = protocol::stylizerSceneToJson(first.scene, first.meshRefs);
    j["occluders"][1]["manipulation"] = {{"closing", {{"radius_px", 3}, {"shape", "box"}}}};
    const server::StylizerSnapshot changed = service->stylizer.setStylizerScene(*s, protocol::stylizerSceneFromJson(j, "", protocol::SceneSource::Api));
    EXPECT_GT(changed.revision, first.revision);
    EXPECT_EQ(changed.scene.occluders[1].manipulation.closingRadius, 3);
    const server::StylizerSnapshot undone = service->stylizer.undoStylizer(*s, false);
    EXPECT_EQ(undone.scene.occluders[1].manipulation.closingRadius, first.scene.occluders[1].manipulation.closingRadius);
    const server::StylizerSnapshot redone = service->stylizer.undoStylizer(*s, true);
    EXPECT_EQ(redone.scene.occluders[1].manipulation.closingRadius, 3);
    try {
        service->stylizer.undoStylizer(*s, true);
        FAIL() << "a redo with nothing to redo";
    } catch (const ApiError& e) {
        EXPECT_EQ(e.code(), ErrorCode::Busy);
    }
}

TEST_F(ServiceTest, SolvesQueueUpToTheLimitWithoutTouchingGl) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    core::SolveOptions options;
    try {
        service->jobs.startSolve(s, options);
        FAIL() << "a solve without targets was queued";
    } catch (const ApiError& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    }
    const auto v = service->sessions.addView(*s, smallCamera());
    service->sessions.setViewImage(*s, v.id, server::ViewImage::Target, targetPng(0.25f));
    auto job = service->jobs.startSolve(s, options);
    EXPECT_EQ(job->state, protocol::JobState::Queued);
    EXPECT_EQ(service->jobs.job(job->id), job);
    service->jobs.startSolve(s, options);
    try {
        service->jobs.startSolve(s, options);
        FAIL() << "a third job was queued over the limit of 2";
    } catch (const ApiError& e) {
        EXPECT_EQ(e.code(), ErrorCode::TooManyJobs);
    }
    EXPECT_EQ(counts->longTasks, 2);
    EXPECT_EQ(counts->shortTasks, 0);
    allowedShortTasks = 1;  // the service's shutdown, which frees what the jobs might have made
}

// Everything above, written to a data folder and read back by a new service (a restart).
TEST_F(ServiceTest, ARestartRestoresEveryRecord) {
    TempDir dir;
    std::string id;
    std::vector<float> current;
    nlohmann::json sceneJson;
    uint64_t revision = 0;
    {
        auto service = makeService(dir.path.string());
        auto s = service->sessions.create(smallCloud());
        id = s->id;
        const auto v = service->sessions.addView(*s, smallCamera());
        service->sessions.setViewImage(*s, v.id, server::ViewImage::Target, targetPng(0.75f));
        service->volumes.perturb(*s, someNoise(7));
        current = volumeOf(*s).extinction();
        const server::StylizerSnapshot first = service->stylizer.stylizer(*s);
        nlohmann::json j = protocol::stylizerSceneToJson(first.scene, first.meshRefs);
        j["occluders"][0]["manipulation"] = {{"closing", {{"radius_px", 2}}}};
        const auto changed = service->stylizer.setStylizerScene(*s, protocol::stylizerSceneFromJson(j, "", protocol::SceneSource::Api));
        sceneJson = protocol::stylizerSceneToJson(changed.scene, changed.meshRefs);
        revision = changed.revision;
    }
    auto service = makeService(dir.path.string());
    auto s = service->sessions.find(id);
    EXPECT_EQ(versionOf(*s), 2);
    EXPECT_EQ(volumeOf(*s).extinction(), current);  // bit for bit
    const server::SessionView v = service->sessions.view(*s, "v1");
    ASSERT_TRUE(v.target.has_value());
    EXPECT_EQ(v.target->pixel(3, 3)[3], 0.75f);  // float EXR: exact
    const server::StylizerSnapshot restored = service->stylizer.stylizer(*s);
    EXPECT_EQ(restored.revision, revision);
    EXPECT_EQ(protocol::stylizerSceneToJson(restored.scene, restored.meshRefs), sceneJson);
    EXPECT_EQ(service->stylizer.undoStylizer(*s, false).scene.occluders[0].manipulation.closingRadius, 0);  // the undo history too
    EXPECT_EQ(service->volumes.revert(*s, 1), 3);  // version 1 is read back from its file
}

// The job record: a job queued when the server stopped reads failed/interrupted after a restart.
TEST_F(ServiceTest, AJobQueuedAtAStopIsInterruptedAfterTheRestart) {
    TempDir dir;
    std::string jobId;
    {
        auto service = makeService(dir.path.string());
        auto s = service->sessions.create(smallCloud());
        const auto v = service->sessions.addView(*s, smallCamera());
        service->sessions.setViewImage(*s, v.id, server::ViewImage::Target, targetPng(0.25f));
        jobId = service->jobs.startSolve(s, core::SolveOptions{})->id;
    }
    allowedShortTasks = 1;  // the first service's shutdown
    auto service = makeService(dir.path.string());
    auto job = service->jobs.job(jobId);
    EXPECT_EQ(job->state, protocol::JobState::Failed);
    ASSERT_TRUE(job->error.has_value());
    EXPECT_EQ(job->error->code, protocol::ErrorCode::Interrupted);
    // Written back: a third start reads the same.
    auto again = makeService(dir.path.string());
    EXPECT_EQ(again->jobs.job(jobId)->state, protocol::JobState::Failed);
}

// Damage: a view's image that does not read is quarantined and the view stays without it; a
// record of a newer format is not guessed at: the session goes to the quarantine whole.
TEST_F(ServiceTest, DamagedFilesGoToTheQuarantineAndOnlyWhatTheyHeldIsLost) {
    TempDir dir;
    std::string damagedView, newerFormat;
    {
        auto service = makeService(dir.path.string());
        auto a = service->sessions.create(smallCloud());
        const auto v = service->sessions.addView(*a, smallCamera());
        service->sessions.setViewImage(*a, v.id, server::ViewImage::Target, targetPng(0.5f));
        damagedView = a->id;
        newerFormat = service->sessions.create(smallCloud())->id;
    }
    const fs::path sessions = dir.path / "sessions";
    {
        std::ofstream broken(sessions / damagedView / "views" / "v1" / "target.exr", std::ios::trunc);
        broken << "not an EXR";
    }
    {
        std::ifstream in(sessions / newerFormat / "session.json");
        nlohmann::json record = nlohmann::json::parse(in);
        record["format"] = 2;
        std::ofstream(sessions / newerFormat / "session.json", std::ios::trunc) << record.dump();
    }
    auto service = makeService(dir.path.string());
    auto s = service->sessions.find(damagedView);
    EXPECT_EQ(service->sessions.view(*s, "v1").target, std::nullopt);
    EXPECT_THROW(service->sessions.find(newerFormat), ApiError);
    const auto quarantine = service->sessions.quarantine();
    ASSERT_EQ(quarantine.size(), 2u);
    bool sawImage = false, sawSession = false;
    for (const auto& q : quarantine) {
        sawImage |= q.session == damagedView && q.file == "views/v1/target.exr";
        sawSession |= q.session == newerFormat && q.file.empty() && q.reason.find("newer") != std::string::npos;
    }
    EXPECT_TRUE(sawImage);
    EXPECT_TRUE(sawSession);
}

// The undo stacks hold core scenes (issue #36); one whose mesh was deleted since no longer
// resolves: the undo to it answers 409 and drops it, and the one before it is next.
TEST_F(ServiceTest, AnUndoToASceneWhoseMeshWasDeletedIsDropped) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    service->stylizer.putOccluderMesh(*s, "tri", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const server::StylizerSnapshot forest = service->stylizer.stylizer(*s);
    nlohmann::json j = protocol::stylizerSceneToJson(forest.scene, forest.meshRefs);
    j["occluders"][0]["mesh"] = "tri";
    service->stylizer.setStylizerScene(*s, protocol::stylizerSceneFromJson(j, "", protocol::SceneSource::Api));
    service->stylizer.setStylizerScene(*s, protocol::stylizerSceneFromJson(protocol::stylizerSceneToJson(forest.scene, forest.meshRefs), "",
                                                                  protocol::SceneSource::Api));
    service->stylizer.removeOccluderMesh(*s, "tri");  // the current scene no longer uses it
    try {
        service->stylizer.undoStylizer(*s, false);
        FAIL() << "undid to a scene whose mesh is gone";
    } catch (const ApiError& e) {
        EXPECT_EQ(e.code(), ErrorCode::Busy);
        EXPECT_NE(std::string(e.what()).find("'tri' was deleted"), std::string::npos) << e.what();
    }
    const server::StylizerSnapshot first = service->stylizer.undoStylizer(*s, false);  // the forest as it was first
    EXPECT_EQ(first.meshRefs, forest.meshRefs);
    EXPECT_EQ(first.scene.occluders[0].mesh, forest.scene.occluders[0].mesh);  // the built-in mesh, shared
}

// Review of #36: undo entries keep what cannot be made again, not layered TFs' compiled images
// (1024² RGBA float is 16 MiB each; 64 entries a stack held gigabytes); an undo compiles again.
TEST_F(ServiceTest, UndoEntriesDoNotHoldCompiledTransferFunctions) {
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    const server::StylizerSnapshot forest = service->stylizer.stylizer(*s);
    nlohmann::json j = protocol::stylizerSceneToJson(forest.scene, forest.meshRefs);
    j["transfer_function"] = {{"size", {256, 256}}, {"layers", {{{"type", "solid"}, {"colour", {0.2, 0.4, 0.6}}, {"alpha", 1.0}}}}};
    service->stylizer.setStylizerScene(*s, protocol::stylizerSceneFromJson(j, "", protocol::SceneSource::Api));
    j["transfer_function"]["layers"][0]["colour"] = {0.9, 0.1, 0.1};
    service->stylizer.setStylizerScene(*s, protocol::stylizerSceneFromJson(j, "", protocol::SceneSource::Api));
    {
        std::lock_guard lock(s->mutex);
        ASSERT_EQ(s->stylizer.undo.size(), 2u);
        const auto& kept = s->stylizer.undo.back().scene.transferFunction;
        ASSERT_TRUE(kept.has_value());
        EXPECT_EQ(kept->image, nullptr) << "an undo entry holds a compiled TF image";
        EXPECT_LT(s->stylizer.undo.back().bytes, size_t(64) << 10);
    }
    const server::StylizerSnapshot undone = service->stylizer.undoStylizer(*s, false);
    ASSERT_TRUE(undone.scene.transferFunction && undone.scene.transferFunction->image);
    EXPECT_EQ(undone.scene.transferFunction->image->width, 256);
    EXPECT_NEAR(undone.scene.transferFunction->image->pixel(10, 10)[2], 0.6f, 1e-6);  // the first TF, compiled again
}

TEST_F(ServiceTest, UndoAndRedoStepThroughEveryVersionShown) {
    // Issue #37: undo steps back through what the session showed (not between the last two
    // versions), redo steps forward, an edit clears redo; each step is a new version holding the
    // content of the one it brings back, and the stacks survive a restart.
    TempDir dir;
    std::string sid;
    std::vector<core::Volume> shown;  // the content of versions 1, 2, 3, 4
    auto sameAs = [&](Session& s, int version) {
        const core::Volume now = volumeOf(s);
        return now.extinction() == shown[size_t(version - 1)].extinction() && now.emission() == shown[size_t(version - 1)].emission();
    };
    auto showsOf = [](Session& s) {
        std::lock_guard lock(s.mutex);
        return std::tuple{s.volume.shows, s.volume.undo.size(), s.volume.redo.size()};
    };
    {
        auto service = makeService(dir.path.string());
        auto s = service->sessions.create(smallCloud());
        sid = s->id;
        shown.push_back(volumeOf(*s));
        for (uint32_t seed : {1u, 2u, 3u}) {
            service->volumes.perturb(*s, someNoise(seed));
            shown.push_back(volumeOf(*s));
        }
        ASSERT_EQ(versionOf(*s), 4);
        for (int back : {3, 2, 1}) {  // three undos: 4 → 3 → 2 → 1, each a new version
            service->volumes.step(*s, false);
            EXPECT_TRUE(sameAs(*s, back)) << "undo should show version " << back;
            EXPECT_EQ(std::get<0>(showsOf(*s)), back);
        }
        EXPECT_EQ(versionOf(*s), 7);
        try {
            service->volumes.step(*s, false);
            FAIL() << "an undo past the first version";
        } catch (const ApiError& e) {
            EXPECT_EQ(e.code(), ErrorCode::Busy);
        }
        service->volumes.step(*s, true);  // redo: 2
        EXPECT_TRUE(sameAs(*s, 2));
        EXPECT_EQ(showsOf(*s), std::tuple(2, size_t(1), size_t(2)));
    }
    auto service = makeService(dir.path.string());  // a restart keeps the stacks
    auto s = service->sessions.find(sid);
    EXPECT_EQ(showsOf(*s), std::tuple(2, size_t(1), size_t(2)));
    service->volumes.step(*s, true);  // redo: 3
    EXPECT_TRUE(sameAs(*s, 3));
    service->volumes.perturb(*s, someNoise(9));  // an edit clears redo
    EXPECT_EQ(std::get<2>(showsOf(*s)), 0u);
    EXPECT_THROW(service->volumes.step(*s, true), ApiError);
    service->volumes.step(*s, false);  // undo: back to 3, what the edit replaced
    EXPECT_TRUE(sameAs(*s, 3));
    service->volumes.revert(*s, 1);  // a revert is an edit that shows version 1
    EXPECT_TRUE(sameAs(*s, 1));
    EXPECT_EQ(std::get<0>(showsOf(*s)), 1);
    service->volumes.step(*s, false);
    EXPECT_TRUE(sameAs(*s, 3)) << "undoing a revert shows what it replaced";
}

TEST_F(ServiceTest, OnlyAChangeBeyondTheTimeIsAStepToUndo) {
    // Scrubbing is not a step; the same layered TF PUT again (compiled again into a new image) is
    // not either; a moved occluder is. Compared as core values, not as their JSON.
    auto service = makeService();
    auto s = service->sessions.create(smallCloud());
    const server::StylizerSnapshot forest = service->stylizer.stylizer(*s);
    nlohmann::json j = protocol::stylizerSceneToJson(forest.scene, forest.meshRefs);
    j["transfer_function"] = {{"size", {64, 64}}, {"layers", {{{"type", "solid"}, {"colour", {0.2, 0.4, 0.6}}, {"alpha", 1.0}}}}};
    auto put = [&] { service->stylizer.setStylizerScene(*s, protocol::stylizerSceneFromJson(j, "", protocol::SceneSource::Api)); };
    auto undoDepth = [&] {
        std::lock_guard lock(s->mutex);
        return s->stylizer.undo.size();
    };
    put();
    ASSERT_EQ(undoDepth(), 1u);
    j["time"] = 2.5;
    put();
    EXPECT_EQ(undoDepth(), 1u) << "a change of time alone";
    put();
    EXPECT_EQ(undoDepth(), 1u) << "the same scene again (its TF compiled again)";
    j["occluders"][0]["colour"] = {0.9, 0.1, 0.1};
    put();
    EXPECT_EQ(undoDepth(), 2u) << "an occluder painted another colour";
}

TEST_F(ServiceTest, AFinishedJobsAnswerIsTheSameAfterARestart) {
    // A job's progress and result are typed values (protocol/job_values.h); its record keeps the
    // answer as it was given, so GET /jobs/{jid} reads the same before and after a restart.
    TempDir dir;
    std::string before, jobId;
    {
        auto service = makeService(dir.path.string());
        auto s = service->sessions.create(smallCloud());
        auto job = service->context.jobs.add(s->id);
        core::SolveProgress p;
        p.iteration = 7;
        p.objective = 0.125;
        p.rmsPerView = {0.5};
        job->report(protocol::SolveJobProgress{p, "lights", 2});
        protocol::LightsJobResult r;
        r.version = 3;
        r.rounds = 2;
        r.rmsHistory = {0.5, 0.25};
        r.totalMs = 12.5;
        r.environmentUrl = "/api/v1/sessions/" + s->id + "/lighting/environment.exr";
        {
            std::lock_guard lock(job->mutex);
            job->state = protocol::JobState::Done;
            job->result = r;
        }
        service->context.saved(*job);
        jobId = job->id;
        const nlohmann::json answer = protocol::jobToJson(job->info());
        EXPECT_EQ(answer["progress"]["block"], "lights");
        EXPECT_EQ(answer["progress"]["round"], 2);
        EXPECT_EQ(answer["progress"]["iteration"], 7);
        EXPECT_EQ(answer["result"]["rounds"], 2);
        EXPECT_EQ(answer["result"]["rms_history"], nlohmann::json({0.5, 0.25}));
        EXPECT_EQ(answer["result"]["version"], 3);
        EXPECT_FALSE(answer["result"].contains("report")) << "a combined solve reports its rounds";
        EXPECT_TRUE(answer["error"].is_null());
        before = answer.dump();
    }
    auto service = makeService(dir.path.string());
    auto job = service->jobs.job(jobId);
    EXPECT_EQ(protocol::jobToJson(job->info()).dump(), before);
    ASSERT_EQ(job->events.size(), 1u) << "a restored job replays its final event";
    EXPECT_EQ(job->events[0].event, protocol::JobEvent::Done);
    EXPECT_EQ(protocol::jobEventDataToJson(job->events[0]).dump(), before);
}

}  // namespace
}  // namespace volstyle

#pragma once
// The HTTP API in-process (cpp-httplib's own test pattern): a server on a free loopback port in a
// thread, stopped by the fixture; every answer checked for status and, on errors, the SPEC's body.
#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "server/http/http_server.h"

namespace volstyle::test {

using json = nlohmann::json;

class Api : public ::testing::Test {
protected:
    /// Starts a server in memory, or on `dataDir` (the durability tests use the real binary).
    void start(server::ServerOptions opt = {}, const std::string& dataDir = "") {
        opt.host = "127.0.0.1";
        opt.port = 0;
        opt.webDir = VOLSTYLE_SOURCE_DIR "/web";
        opt.maxJsonBytes = 4096;
        opt.maxUploadBytes = m_maxUploadBytes;
        opt.maxImageSide = 64;
        opt.dataDir = dataDir;
        opt.store = testStore();
        opt.vdbReader = VOLSTYLE_BINARY;  // uploads are read in a child, as `serve` does
        try {
            m_server = std::make_unique<server::HttpServer>(opt);
        } catch (const GpuError& e) {
            const char* required = std::getenv("VOLSTYLE_GL_REQUIRED");  // .ci/run: fail, never skip
            if (required && std::string(required) != "" && std::string(required) != "0")
                GTEST_FAIL() << "no EGL/OpenGL 4.5 context (VOLSTYLE_GL_REQUIRED): " << e.what();
            GTEST_SKIP() << "no EGL/OpenGL 4.5 context: " << e.what();
        }
        m_port = m_server->bind();
        m_thread = std::thread([this] { m_server->listen(); });
        m_client = std::make_unique<httplib::Client>("127.0.0.1", m_port);
        m_client->set_read_timeout(120, 0);  // sanitizer builds take seconds to build a scene
        for (int i = 0; i < 100 && !m_client->Get("/api/v1/health"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    void SetUp() override { start(); }
    void TearDown() override {
        if (m_server) m_server->stop();
        if (m_thread.joinable()) m_thread.join();
        m_server.reset();
        if (!m_database.empty()) psql("DROP DATABASE " + std::exchange(m_database, "") + " WITH (FORCE)");
    }

    /// With $VOLSTYLE_TEST_STORE (tests/cluster/with_postgres.sh: the suite run against the
    /// PostgreSQL store, issue #41), a database of this test's own, made at its first start.
    std::string testStore() {
        const char* url = std::getenv("VOLSTYLE_TEST_STORE");
        if (!url || !*url) return "";
        const std::string base = url;
        if (m_database.empty()) {
            static int counter = 0;
            m_database = "volstyle_test_" + std::to_string(::getpid()) + "_" + std::to_string(++counter);
            psql("CREATE DATABASE " + m_database);
        }
        return base.substr(0, base.rfind('/') + 1) + m_database;
    }
    static void psql(const std::string& sql) {
        const std::string command = "psql \"" + std::string(std::getenv("VOLSTYLE_TEST_STORE")) + "\" -qc \"" + sql + "\" > /dev/null";
        ASSERT_EQ(std::system(command.c_str()), 0) << command;
    }
    std::string m_database;
    httplib::Client& client() { return *m_client; }

    /// Checks the SPEC's error body and returns it.
    json expectError(const httplib::Result& r, int status, const std::string& code) {
        EXPECT_TRUE(r) << "no answer";
        if (!r) return {};
        EXPECT_EQ(r->status, status) << r->body;
        EXPECT_EQ(r->get_header_value("Content-Type"), "application/json");
        json j = json::parse(r->body);
        EXPECT_EQ(j["error"]["code"], code) << r->body;
        EXPECT_FALSE(j["error"]["message"].get<std::string>().empty());
        EXPECT_TRUE(j["error"]["details"].is_array());
        EXPECT_FALSE(j["error"]["request_id"].get<std::string>().empty());
        return j;
    }

    std::string createSession(int resolution = 16) {
        auto r = client().Post("/api/v1/sessions", json{{"scene", "builtin:sphere"}, {"resolution", resolution}}.dump(), "application/json");
        EXPECT_EQ(r->status, 201) << r->body;
        return json::parse(r->body)["id"];
    }

    std::unique_ptr<server::HttpServer> m_server;
    std::unique_ptr<httplib::Client> m_client;
    std::thread m_thread;
    int m_port = 0;
    size_t m_maxUploadBytes = 64 * 1024;  ///< small, so the limit is cheap to test
};


/// A server on a data directory of its own, restartable (durability checks).
class PersistentApi : public Api {
protected:
    void SetUp() override {
        m_dir = std::filesystem::temp_directory_path() / ("volstyle-api-" + std::to_string(::getpid()));
        std::filesystem::remove_all(m_dir);
        start({}, m_dir.string());
    }
    void TearDown() override {
        Api::TearDown();
        std::filesystem::remove_all(m_dir);
    }
    void restart() {
        m_server->stop();
        m_thread.join();
        m_server.reset();
        // Against a store, the folder is its cache: a restart with an empty one proves that
        // everything acknowledged was committed there.
        if (!m_database.empty()) std::filesystem::remove_all(m_dir);
        start({}, m_dir.string());
    }
    std::filesystem::path m_dir;
};

inline std::string pngOf(const core::Image& img) { return core::encodeImage(img, "png"); }

/// Reads an SSE stream to its end; returns the event names in order.
inline std::vector<std::string> readEvents(httplib::Client& c, const std::string& path) {
    std::string buffer;
    std::vector<std::string> names;
    c.set_read_timeout(120, 0);
    c.Get(path.c_str(), [&](const char* data, size_t n) {
        buffer.append(data, n);
        for (size_t pos; (pos = buffer.find("\n\n")) != std::string::npos;) {
            std::string block = buffer.substr(0, pos);
            buffer.erase(0, pos + 2);
            if (block.rfind("event: ", 0) == 0) names.push_back(block.substr(7, block.find('\n') - 7));
        }
        return true;
    });
    return names;
}

/// Starts a solve with `options` and follows its events to the end; the finished job's JSON
/// (state "done" expected by the caller), or {} when the solve was refused.
inline json solveToEnd(httplib::Client& c, const std::string& base, const std::string& options) {
    auto r = c.Post((base + "/solve").c_str(), options, "application/json");
    EXPECT_EQ(r->status, 202) << r->body;
    if (r->status != 202) return {};
    const std::string job = json::parse(r->body)["job"];
    const auto events = readEvents(c, "/api/v1/jobs/" + job + "/events");
    EXPECT_FALSE(events.empty());
    if (!events.empty()) {
        EXPECT_EQ(events.back(), "done");
    }
    return json::parse(c.Get(("/api/v1/jobs/" + job).c_str())->body);
}

/// A solve report's mean initial and final RMS over its views.
inline std::pair<double, double> meanRms(const json& report) {
    double before = 0, after = 0;
    const size_t n = report["initial_rms"].size();
    for (size_t v = 0; v < n; ++v) before += report["initial_rms"][v].get<double>(), after += report["final_rms"][v].get<double>();
    return {before / double(std::max<size_t>(n, 1)), after / double(std::max<size_t>(n, 1))};
}

/// Adds a `size`² view looking down -z and uploads a constant target; returns the view id.
inline std::string addConstantTargetView(httplib::Client& c, const std::string& base, int size, float value) {
    json camera = {{"camera", {{"eye", {0, 0, 3}}, {"target", {0, 0, 0}}, {"width", size}, {"height", size}}}};
    std::string vid = json::parse(c.Post((base + "/views").c_str(), camera.dump(), "application/json")->body)["id"];
    core::Image target(size, size);
    for (float& x : target.rgba) x = value;
    EXPECT_EQ(c.Put((base + "/views/" + vid + "/target").c_str(), pngOf(target), "image/png")->status, 200);
    return vid;
}


}  // namespace volstyle::test

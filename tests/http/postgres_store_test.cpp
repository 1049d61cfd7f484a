// The PostgreSQL store (issue #41 item 1), run only under tests/cluster/with_postgres.sh (CTest
// store_postgresql; the whole HTTP suite runs against the store there too, as http_postgresql):
// every acknowledged change is committed to the database (a server started on an empty folder
// restores it), a second server on the same database sees what the first wrote, the schema is
// versioned and a database newer than the binary is refused, and files are large objects.
#include <gtest/gtest.h>

#include <cstdio>

#include "api_fixture.h"
#include "protocol/error_body.h"
#include "server/store/file_mirror.h"

using namespace volstyle;
using namespace volstyle::test;

namespace {

class PostgresStore : public PersistentApi {
protected:
    void SetUp() override {
        ASSERT_TRUE(std::getenv("VOLSTYLE_TEST_STORE")) << "run under tests/cluster/with_postgres.sh";
        PersistentApi::SetUp();
    }
    /// One value of a query on this test's database (psql -At).
    std::string query(const std::string& sql) {
        const std::string command = "psql \"" + testStore() + "\" -Atc \"" + sql + "\"";
        std::string out;
        if (FILE* p = ::popen(command.c_str(), "r")) {
            char buffer[256];
            while (std::fgets(buffer, sizeof buffer, p)) out += buffer;
            EXPECT_EQ(::pclose(p), 0) << command;
        }
        while (!out.empty() && out.back() == '\n') out.pop_back();
        return out;
    }
};

}  // namespace

TEST_F(PostgresStore, EveryAcknowledgedChangeIsInTheDatabase) {
    const std::string id = createSession(16), base = "/api/v1/sessions/" + id;
    ASSERT_EQ(client().Post((base + "/refraction").c_str(), R"({"index": 1.3, "radius": 0.5})", "application/json")->status, 200);
    const std::string view = addConstantTargetView(client(), base, 16, 0.5f);
    // Rows as large objects, by path: the record, both versions, the view's target.
    EXPECT_EQ(query("SELECT count(*) FROM volstyle_files WHERE path LIKE 'sessions/" + id + "/versions/%.vdb'"), "2");
    EXPECT_EQ(query("SELECT count(*) FROM volstyle_files WHERE path = 'sessions/" + id + "/session.json'"), "1");
    EXPECT_EQ(query("SELECT count(*) FROM volstyle_files WHERE path LIKE 'sessions/" + id + "/views/" + view + "/%'"), "1");
    EXPECT_EQ(query("SELECT count(*) FROM volstyle_files f LEFT JOIN pg_largeobject_metadata m ON m.oid = f.object WHERE m.oid IS NULL"), "0")
        << "every row names a large object";
    const std::string before = client().Get(base.c_str())->body;
    restart();  // on an empty folder: only the database holds the session
    const json after = json::parse(client().Get(base.c_str())->body);
    EXPECT_EQ(after["volume"]["version"], 2);
    EXPECT_EQ(after["views"].size(), 1u);
    EXPECT_EQ(json::parse(before)["volume"]["grids"], after["volume"]["grids"]);
    // A deleted session leaves nothing behind, large objects included.
    const std::string objects = query("SELECT count(*) FROM pg_largeobject_metadata");
    ASSERT_EQ(client().Delete(base.c_str())->status, 204);
    EXPECT_EQ(query("SELECT count(*) FROM volstyle_files WHERE path LIKE 'sessions/" + id + "/%'"), "0");
    EXPECT_LT(std::stoi(query("SELECT count(*) FROM pg_largeobject_metadata")), std::stoi(objects));
}

TEST_F(PostgresStore, ASecondServerOnTheDatabaseStartsWithWhatTheFirstWrote) {
    const std::string id = createSession(16);
    server::ServerOptions opt;
    opt.host = "127.0.0.1";
    opt.port = 0;
    opt.dataDir = (m_dir / "second").string();  // a folder of its own
    opt.store = testStore();
    opt.vdbReader = VOLSTYLE_BINARY;
    server::HttpServer second(opt);
    const int port = second.bind();
    std::thread t([&] { second.listen(); });
    httplib::Client c("127.0.0.1", port);
    auto r = c.Get(("/api/v1/sessions/" + id).c_str());
    second.stop();
    t.join();
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << r->body;
}

TEST_F(PostgresStore, ASchemaNewerThanTheBinaryIsRefused) {
    EXPECT_EQ(query("SELECT version FROM volstyle_schema"), std::to_string(server::kStoreSchemaVersion));
    m_server->stop();
    m_thread.join();
    m_server.reset();
    query("UPDATE volstyle_schema SET version = 99");
    server::ServerOptions opt;
    opt.dataDir = m_dir.string();
    opt.store = testStore();
    try {
        server::HttpServer refused(opt);
        ADD_FAILURE() << "a server started on a schema newer than its own";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("schema is version 99, newer than this binary's"), std::string::npos) << e.what();
    }
    query("UPDATE volstyle_schema SET version = " + std::to_string(server::kStoreSchemaVersion));
}

TEST_F(PostgresStore, AStaleCopysFilesAreRefusedAndNothingIsWritten) {
    // A view's image, a frame, an upload: written under the session record's stamp check, as the
    // record itself is. Two handles on the store play two replicas.
    auto mirror = server::openPostgresMirror(testStore());
    const std::filesystem::path local = m_dir / "probe.bin";
    std::FILE* f = std::fopen(local.c_str(), "wb");
    ASSERT_TRUE(f);
    std::fputs("probe", f);
    std::fclose(f);
    const std::string record = "sessions/0123abcd/session.json", dir = "sessions/0123abcd/views/v1/";
    const uint64_t first = mirror->putRecord(record, local, {}, 0);
    const server::RecordGuard current{record, first};
    mirror->put(dir + "target.exr", local, &current);  // the newest copy writes
    mirror->putRecord(record, local, {}, first);         // another replica saves the session
    const server::RecordGuard stale{record, first};
    EXPECT_THROW(mirror->put(dir + "weights.exr", local, &stale), protocol::ApiError);
    EXPECT_THROW(mirror->remove(dir + "target.exr", &stale), protocol::ApiError);
    EXPECT_THROW(mirror->removeTree("sessions/0123abcd/views/v1", &stale), protocol::ApiError);
    EXPECT_EQ(query("SELECT count(*) FROM volstyle_files WHERE path = '" + dir + "weights.exr'"), "0");
    EXPECT_EQ(query("SELECT count(*) FROM volstyle_files WHERE path = '" + dir + "target.exr'"), "1") << "the stale copy removed nothing";
}

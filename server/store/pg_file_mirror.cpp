// The PostgreSQL file mirror (file_mirror.h). Each file is a large object (streamed from and to
// the local file by libpq's lo_import/lo_export: never whole in memory) named by a row of
// volstyle_files; a put replaces the row and unlinks the old object in one transaction, so a
// reader sees the old file or the new one, never a part. Migrations are numbered, applied at
// start under an advisory lock (replicas starting together apply each once), and a schema newer
// than this binary's is refused.
#include <spdlog/spdlog.h>

#include <regex>

#include "server/store/data_dir.h"
#include "server/store/pg_connection.h"

namespace volstyle::server {

namespace {

namespace fs = std::filesystem;

/// Migration k (1-based) takes the schema from version k-1 to k.
const char* const kMigrations[] = {
    // 1: files as large objects by path.
    "CREATE TABLE volstyle_files (path text PRIMARY KEY, object oid NOT NULL, bytes bigint NOT NULL, "
    "written timestamptz NOT NULL DEFAULT now())",
    // 2: the job queue (pg_job_queue.cpp): a row per job, leased by the replica running it.
    "CREATE TABLE volstyle_jobs (id text PRIMARY KEY, session text NOT NULL, kind text NOT NULL, inputs text NOT NULL, "
    "state text NOT NULL, record text NOT NULL, owner text, lease_until timestamptz, attempts integer NOT NULL DEFAULT 1, "
    "cancel boolean NOT NULL DEFAULT false, created timestamptz NOT NULL DEFAULT clock_timestamp()); "
    "CREATE INDEX volstyle_jobs_lapsed ON volstyle_jobs (lease_until) WHERE state IN ('queued', 'running')",
};
static_assert(std::size(kMigrations) == kStoreSchemaVersion, "a migration for every schema version");

/// An arbitrary constant: the advisory lock the migrations take.
constexpr long long kMigrationLock = 0x766f6c7374796c65;  // "volstyle"

class PgFileMirror final : public FileMirror {
public:
    explicit PgFileMirror(const std::string& url) : m_db(url) { migrate(); }

    uint64_t put(const std::string& path, const fs::path& local, const RecordGuard* guard) override {
        uint64_t stamp = 0;
        run("store " + path, [&](pqxx::work& tx) {
            if (guard) checkRecord(tx, guard->record, guard->expected);
            stamp = putIn(tx, path, local);
        });
        return stamp;
    }

    uint64_t putRecord(const std::string& record, const fs::path& recordLocal, const std::vector<std::pair<std::string, fs::path>>& files,
                       uint64_t expected) override {
        uint64_t stamp = 0;
        run("store " + record, [&](pqxx::work& tx) {
            checkRecord(tx, record, expected);
            for (const auto& [path, local] : files) putIn(tx, path, local);
            stamp = putIn(tx, record, recordLocal);
        });
        return stamp;
    }

    std::optional<uint64_t> stamp(const std::string& path) override {
        std::optional<uint64_t> out;
        run("read the stamp of " + path, [&](pqxx::work& tx) {
            const pqxx::result r = tx.exec_params("SELECT object FROM volstyle_files WHERE path = $1", path);
            out = r.empty() ? std::nullopt : std::optional<uint64_t>(r[0][0].as<pqxx::oid>());
        });
        return out;
    }

    void remove(const std::string& path, const RecordGuard* guard) override {
        run("remove " + path, [&](pqxx::work& tx) {
            if (guard) checkRecord(tx, guard->record, guard->expected);
            for (const auto& row : tx.exec_params("DELETE FROM volstyle_files WHERE path = $1 RETURNING object", path))
                pqxx::largeobject(row[0].as<pqxx::oid>()).remove(tx);
        });
    }

    void removeTree(const std::string& prefix, const RecordGuard* guard) override {
        run("remove " + prefix, [&](pqxx::work& tx) {
            if (guard) checkRecord(tx, guard->record, guard->expected);
            const std::string like = escapeLike(prefix) + "/%";
            for (const auto& row : tx.exec_params("DELETE FROM volstyle_files WHERE path = $1 OR path LIKE $2 RETURNING object", prefix, like))
                pqxx::largeobject(row[0].as<pqxx::oid>()).remove(tx);
        });
    }

    size_t materializeTree(const std::string& prefix, const fs::path& root, const std::string& record,
                           std::optional<uint64_t>* recordStamp) override {
        size_t n = 0;
        run("read the stored files", [&](pqxx::work& tx) {
            // One snapshot: the files and the record's stamp as of one moment, and a concurrent
            // put's unlink cannot remove an object this export still reads.
            tx.exec("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ");
            n = 0;
            if (recordStamp) {
                const pqxx::result r = tx.exec_params("SELECT object FROM volstyle_files WHERE path = $1", record);
                *recordStamp = r.empty() ? std::nullopt : std::optional<uint64_t>(r[0][0].as<pqxx::oid>());
            }
            for (const auto& row :
                 tx.exec_params("SELECT path, object FROM volstyle_files WHERE path LIKE $1 ORDER BY written, path", escapeLike(prefix) + "/%")) {
                const std::string path = row[0].as<std::string>();
                if (path.find("..") != std::string::npos || path.empty() || path[0] == '/') throw IoError("a stored path is not relative: '" + path + "'");
                const fs::path to = root / path;
                fs::create_directories(to.parent_path());
                pqxx::largeobject(row[1].as<pqxx::oid>()).to_file(tx, to.string());
                ++n;
            }
        });
        return n;
    }

    std::vector<std::pair<std::string, std::string>> readEach(const std::string& prefix,
                                                              const std::vector<std::pair<std::string, bool>>& names) override {
        std::vector<std::pair<std::string, std::string>> out;
        run("read the stored files", [&](pqxx::work& tx) {
            tx.exec("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ");  // every name as of one moment
            out.clear();
            for (const auto& [name, content] : names) {
                const std::string query = content ? "SELECT path, convert_from(lo_get(object), 'UTF8') FROM volstyle_files WHERE path LIKE $1"
                                                  : "SELECT path, '' FROM volstyle_files WHERE path LIKE $1";
                for (const auto& row : tx.exec_params(query, escapeLike(prefix) + "/%/" + escapeLike(name))) {
                    const std::string path = row[0].as<std::string>();
                    if (path.find('/', prefix.size() + 1) != path.size() - name.size() - 1) continue;  // one folder deep only
                    out.emplace_back(path, row[1].as<std::string>());
                }
            }
        });
        return out;
    }

    std::string writeProblem() override {
        try {
            run("check", [](pqxx::work& tx) { tx.exec("SELECT 1 FROM volstyle_files LIMIT 1"); });
            return "";
        } catch (const std::exception& e) {
            return e.what();
        }
    }

    std::string describe() const override { return m_db.describe(); }

private:
    /// Locks `record`'s row for the transaction and checks that its stamp is still `expected`
    /// (0: no record yet); ApiError busy when another replica changed the session meanwhile.
    static void checkRecord(pqxx::work& tx, const std::string& record, uint64_t expected) {
        // A new session's record cannot be locked before it exists: an advisory lock on its
        // path's hash serializes two first saves too.
        tx.exec_params("SELECT pg_advisory_xact_lock(hashtext($1))", record);
        const pqxx::result r = tx.exec_params("SELECT object FROM volstyle_files WHERE path = $1 FOR UPDATE", record);
        const uint64_t now = r.empty() ? 0 : r[0][0].as<pqxx::oid>();
        if (now != expected)
            throw protocol::ApiError(protocol::ErrorCode::Busy, "another replica changed this session meanwhile (" + record +
                                                                   "); nothing of this request was kept: read the session and retry");
    }

    /// Replaces `path`'s file with the one at `local` within `tx`; the new stamp (a new large
    /// object's id: never the same for two puts while both exist).
    static uint64_t putIn(pqxx::work& tx, const std::string& path, const fs::path& local) {
        // Two first puts of one path would both find no row, and the loser's object would be
        // left unnamed: the path's advisory lock orders them.
        tx.exec_params("SELECT pg_advisory_xact_lock(hashtext($1))", path);
        const pqxx::largeobject object(tx, local.string());
        const pqxx::result old = tx.exec_params("SELECT object FROM volstyle_files WHERE path = $1 FOR UPDATE", path);
        tx.exec_params("INSERT INTO volstyle_files (path, object, bytes) VALUES ($1, $2, $3) ON CONFLICT (path) DO UPDATE "
                       "SET object = EXCLUDED.object, bytes = EXCLUDED.bytes, written = now()",
                       path, object.id(), static_cast<long long>(fs::file_size(local)));
        for (const auto& row : old) pqxx::largeobject(row[0].as<pqxx::oid>()).remove(tx);
        return object.id();
    }

    static std::string escapeLike(const std::string& s) {
        std::string out;
        for (char ch : s) {
            if (ch == '%' || ch == '_' || ch == '\\') out += '\\';
            out += ch;
        }
        return out;
    }

    void migrate() {
        run("migrate the schema", [](pqxx::work& tx) {
            tx.exec("SELECT pg_advisory_xact_lock(" + std::to_string(kMigrationLock) + ")");
            tx.exec("CREATE TABLE IF NOT EXISTS volstyle_schema (version integer NOT NULL)");
            const pqxx::result r = tx.exec("SELECT version FROM volstyle_schema");
            const int at = r.empty() ? 0 : r[0][0].as<int>();
            if (at > kStoreSchemaVersion)
                throw IoError("the store's schema is version " + std::to_string(at) + ", newer than this binary's (" +
                              std::to_string(kStoreSchemaVersion) + "): run a newer volstyle");
            for (int v = at; v < kStoreSchemaVersion; ++v) tx.exec(kMigrations[v]);
            if (r.empty()) tx.exec("INSERT INTO volstyle_schema VALUES (" + std::to_string(kStoreSchemaVersion) + ")");
            else tx.exec("UPDATE volstyle_schema SET version = " + std::to_string(kStoreSchemaVersion));
            if (at < kStoreSchemaVersion) spdlog::info("store: schema migrated from version {} to {}", at, kStoreSchemaVersion);
        });
    }

    template <typename F>
    void run(const std::string& what, F&& body) {
        m_db.run(what, std::forward<F>(body));
    }

    PgConnection m_db;
};

}  // namespace

std::unique_ptr<FileMirror> openPostgresMirror(const std::string& url) { return std::make_unique<PgFileMirror>(url); }

std::string withoutPassword(const std::string& url) { return std::regex_replace(url, std::regex(R"((://[^:/@]+):[^@]*@)"), "$1@"); }

}  // namespace volstyle::server

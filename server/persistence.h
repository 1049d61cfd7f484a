#pragma once
/// \file persistence.h
/// Durability (SPEC §3): every change to a session or job is written to the data directory before
/// the answer is sent — atomically (temporary file, fsync, rename) — and everything is restored
/// when the server starts. Jobs that were queued or running when the server stopped read
/// `failed` with code `interrupted`.
///
/// Layout: DIR/sessions/<sid>/session.json, versions/<N>.vdb, views/<vid>/{target,weights}.exr;
/// DIR/jobs/<jid>.json.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "server/job_store.h"
#include "server/session_store.h"

namespace volstyle::server {

class Persistence {
public:
    explicit Persistence(std::filesystem::path dir);

    /// Writes session.json and any version not on disk yet. Call with the session's mutex held.
    void saveSession(const Session& s);
    void saveViewImage(const std::string& session, const std::string& view, const std::string& kind, const core::Image& image);
    void removeView(const std::string& session, const std::string& view);
    void removeSession(const std::string& session);
    void saveJob(const Job& job);

    std::vector<std::shared_ptr<Session>> loadSessions();
    /// Loads jobs; unfinished ones become failed/interrupted (and are written back).
    std::vector<std::shared_ptr<Job>> loadJobs();

    /// Writes `bytes` to `path` atomically: a temporary file beside it, fsync, rename.
    static void atomicWrite(const std::filesystem::path& path, const std::string& bytes);

private:
    std::filesystem::path sessionDir(const std::string& id) const { return m_dir / "sessions" / id; }
    std::filesystem::path m_dir;
};

}  // namespace volstyle::server

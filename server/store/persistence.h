#pragma once
/// \file persistence.h
/// Durability (SPEC §3): every change to a session or job is written to the data directory before
/// the answer is sent — atomically and durably (store/data_dir.h: temporary file, fsync, rename,
/// fsync of the folder; every step's failure an IoError) — and everything is restored
/// when the server starts. Jobs that were queued or running when the server stopped read
/// `failed` with code `interrupted`.
///
/// Layout: DIR/sessions/<sid>/session.json, versions/<N>.vdb, views/<vid>/{target,weights,background}.exr,
/// frames/<n>.vdb (an animation's frames);
/// DIR/jobs/<jid>.json; DIR/quarantine/.
///
/// Damage (issue #9): a file found unreadable is moved to DIR/quarantine/<sid>/<file> beside a
/// `<file>.reason.json`, and only what it held is lost: a damaged old version stays listed as
/// damaged, a damaged target leaves its view without one, a damaged current version falls back
/// to the newest readable one. A session whose session.json is unreadable (or that has no
/// readable version) moves whole to DIR/quarantine/<sid>/session/. Versions are not read on
/// start (only the current one is): their sizes, recorded when written, are checked instead, and
/// again before a version is read back or sent.
///
/// The facade of server/store: DataDir (the atomic write and the quarantine) and one record type
/// per feature with its own encoder — session_record.h (session.json and the files beside it),
/// stylizer_record.h, job_record.h — so the disk format does not follow the API's answers.

#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "server/state/job_store.h"
#include "server/state/session_store.h"
#include "server/store/data_dir.h"
#include "server/store/file_mirror.h"

namespace volstyle::server {

using store::QuarantineEntry;

class Persistence {
public:
    /// Stored meshes are read again with `readMesh` (the server's child reader: a stored file is
    /// as untrusted as it was when it was uploaded); empty: in this process.
    using MeshReader = std::function<core::Mesh(const std::string& bytes, const std::string& format)>;
    /// With a `mirror` (serve --store postgresql://…) the folder is a cache: it is emptied and
    /// filled from the mirror here, and every write below is committed to the mirror too before
    /// it returns (acknowledged = committed).
    explicit Persistence(std::filesystem::path dir, MeshReader readMesh = {}, std::unique_ptr<FileMirror> mirror = nullptr);
    /// "folder" or the mirror's description.
    std::string describe() const;
    bool hasMirror() const { return m_mirror != nullptr; }
    /// With a mirror: the stamp of session `id`'s record there now (nullopt: no such session).
    std::optional<uint64_t> storedStamp(const std::string& id);
    /// With a mirror: session `id` as the mirror holds it now (another replica may have written
    /// it), its folder here replaced; nullptr when the mirror has none.
    std::shared_ptr<Session> loadFromStore(const std::string& id);
    /// Every session in the store (GET /sessions across replicas): the summary each record's save
    /// wrote beside it (the session as GET /sessions/{sid} answered then, JSON), by id; `unsummed`:
    /// sessions whose record has no summary (saved by an older volstyle).
    struct StoredSessions {
        std::vector<std::pair<std::string, std::string>> summaries;
        std::vector<std::string> unsummed;
    };
    StoredSessions storedSessions();
    /// Session `id`'s summary written to the store for a record that has none (saved by an older
    /// volstyle), from the record and files read there; nullopt when it is gone. Call only for a
    /// session this replica does not hold (its folder here is replaced, then removed).
    std::optional<std::string> summarizeStored(const std::string& id);

    /// Writes session.json and any version not on disk yet (marking it stored). Call with the
    /// session's mutex held.
    void saveSession(Session& s, const std::vector<std::filesystem::path>& alsoCommit = {});
    void saveViewImage(const std::string& session, const std::string& view, const std::string& kind, const core::Image& image);
    void removeViewImage(const std::string& session, const std::string& view, const std::string& kind);
    void removeView(const std::string& session, const std::string& view);
    void removeSession(const std::string& session);
    /// A stylizer change (ServiceContext::stylizerChanged): the scene as revision `revision`
    /// (stylizer/scene.json: its meshes named as the client named them), and with `history` its
    /// undo and redo stacks (stylizer/history.json: written only when they change, not for each
    /// frame of a played path). With a mirror they are committed with the session's
    /// record, under its stamp check: a replica whose copy is stale is refused (409) and writes
    /// nothing, and the record's new stamp tells the others to read the session again.
    void commitStylizer(Session& s, bool history, uint64_t revision);
    /// An uploaded file as it was sent (the stylizer's, environment.image), atomically.
    void saveSessionFile(const std::string& session, const std::string& file, const std::string& bytes);
    void removeSessionFile(const std::string& session, const std::string& file);
    /// A frame of the session's animation (frames/<n>.vdb), atomically; removeFrame deletes it.
    void saveFrame(const std::string& session, int frame, const core::Volume& volume);
    void removeFrame(const std::string& session, int frame);
    void saveJob(const Job& job);
    void removeJob(const std::string& job);  ///< its record and its files
    /// With a mirror: the files a finished job wrote (a sequence's frames and video), committed
    /// there, so that whichever replica answers for the job can send them.
    void saveJobFiles(const std::string& job);
    /// With a mirror: a job's files as the mirror holds them, written here; whether there were any.
    bool fetchJobFiles(const std::string& job);
    /// The folder of a job's files (a sequence's frames and video).
    std::filesystem::path jobFilesDir(const std::string& job) const { return m_dir.jobsDir() / job; }

    /// The bytes of a stored version's file, unchanged (IoError if missing or not the size it
    /// was written with).
    std::string readVersionFile(const std::string& session, int version, std::uintmax_t expectedBytes) const;
    /// A stored version read back (IoError if it is damaged).
    core::Volume loadVersion(const std::string& session, int version, std::uintmax_t expectedBytes) const;
    /// Moves a session's file (relative to its directory) to the quarantine with its reason.
    void quarantineFile(const std::string& session, const std::string& file, const std::string& reason);
    std::vector<QuarantineEntry> quarantine() const;
    /// Whether the data folder takes a write now (GET /ready): "" or what failed. Writes and
    /// removes a small file, as a session's save would.
    std::string writeProblem() const;

    std::vector<std::shared_ptr<Session>> loadSessions();
    /// Loads jobs; unfinished ones become failed/interrupted (and are written back).
    std::vector<std::shared_ptr<Job>> loadJobs();

    static std::string versionFile(int version);

private:
    std::filesystem::path sessionDir(const std::string& id) const { return m_dir.sessionDir(id); }
    /// Restores one session folder (its record, files and stylizer); throws if nothing of it is usable.
    /// `stamp`: its record's stamp in the mirror when its files were read (0: none).
    std::shared_ptr<Session> loadSession(const std::filesystem::path& dir, uint64_t stamp = 0);
    /// The mirror's copy of a file just written, of one removed, of a folder removed. With a
    /// `session`, under its record's stamp check (guardOf): a copy of the session that another
    /// replica changed since is refused (409) and writes nothing.
    void mirrorPut(const std::filesystem::path& file, const std::string& session = "");
    void mirrorRemove(const std::filesystem::path& file, const std::string& session = "");
    void mirrorRemoveTree(const std::filesystem::path& dir, const std::string& session = "");
    /// The guard of session `session`'s files: its record's stamp as this replica last wrote or
    /// read it (nullopt without a session).
    std::optional<RecordGuard> guardOf(const std::string& session);
    void knownStamp(const std::string& session, uint64_t stamp);
    std::string relative(const std::filesystem::path& p) const { return p.lexically_relative(m_dir.root()).generic_string(); }

    store::DataDir m_dir;
    std::unique_ptr<FileMirror> m_mirror;
    std::mutex m_stampsMutex;
    std::map<std::string, uint64_t> m_stamps;  ///< each session's record stamp as last written or read here
    MeshReader m_readMesh;
};

}  // namespace volstyle::server

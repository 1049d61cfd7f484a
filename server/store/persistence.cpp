#include "server/store/persistence.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <set>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/volume/vdb_io.h"
#include "protocol/stylize_json.h"
#include "server/store/job_record.h"
#include "server/store/session_record.h"
#include "server/store/stylizer_record.h"

namespace volstyle::server {

namespace fs = std::filesystem;
using json = nlohmann::json;

Persistence::Persistence(fs::path dir, MeshReader readMesh, std::unique_ptr<FileMirror> mirror)
    : m_dir(std::move(dir)), m_mirror(std::move(mirror)), m_readMesh(std::move(readMesh)) {
    if (!m_mirror) return;
    // The folder is a cache of the mirror: what another replica wrote is in the mirror, and
    // what is only here (a session deleted elsewhere) must not come back. Sessions are read when
    // first asked for (ServiceContext::freshFromStore): a replica starts in the time its jobs'
    // records take to read, not the whole store's.
    for (const char* sub : {"sessions", "jobs"}) {
        fs::remove_all(m_dir.root() / sub);
        fs::create_directories(m_dir.root() / sub);
    }
    // Job records are not read back from here: the job queue holds them (a replica reads a job
    // another one runs from its row, and runs again one whose replica died).
    spdlog::info("store: {}; sessions are read when first asked for", m_mirror->describe());
}

std::optional<uint64_t> Persistence::storedStamp(const std::string& id) {
    return m_mirror ? m_mirror->stamp("sessions/" + id + "/session.json") : std::nullopt;
}

std::shared_ptr<Session> Persistence::loadFromStore(const std::string& id) {
    if (!m_mirror) return nullptr;
    const fs::path dir = sessionDir(id);
    fs::remove_all(dir);
    std::optional<uint64_t> stamp;
    m_mirror->materializeTree("sessions/" + id, m_dir.root(), "sessions/" + id + "/session.json", &stamp);
    if (!stamp || !fs::exists(dir / "session.json")) return nullptr;  // none, or deleted meanwhile
    return loadSession(dir, *stamp);
}

Persistence::StoredSessions Persistence::storedSessions() {
    StoredSessions out;
    if (!m_mirror) return out;
    // "sessions/<sid>/summary.json" → <sid>
    const auto idOf = [](const std::string& path) { return path.substr(9, path.find('/', 9) - 9); };
    std::set<std::string> summed, recorded;
    for (auto& [path, text] : m_mirror->readEach("sessions", {{"summary.json", true}, {"session.json", false}})) {
        if (path.ends_with("/summary.json")) {
            summed.insert(idOf(path));
            out.summaries.emplace_back(idOf(path), std::move(text));
        } else {
            recorded.insert(idOf(path));
        }
    }
    for (const std::string& id : recorded)
        if (!summed.count(id)) out.unsummed.push_back(id);
    return out;
}

std::optional<std::string> Persistence::summarizeStored(const std::string& id) {
    std::shared_ptr<Session> s = loadFromStore(id);
    if (!s) return std::nullopt;  // deleted meanwhile
    std::string text;
    {
        std::lock_guard lock(s->mutex);
        text = store::encodeSessionSummary(*s);
    }
    const fs::path file = sessionDir(id) / "summary.json";
    store::atomicWrite(file, text);
    // Under the record's stamp: a save meanwhile wrote a newer summary, and this one is refused.
    const RecordGuard guard{relative(sessionDir(id) / "session.json"), s->storeStamp};
    m_mirror->put(relative(file), file, &guard);
    s.reset();
    fs::remove_all(sessionDir(id));  // a cache of a session this replica does not hold
    return text;
}

std::string Persistence::describe() const { return m_mirror ? m_mirror->describe() : "folder"; }

void Persistence::mirrorPut(const fs::path& file, const std::string& session) {
    if (!m_mirror) return;
    const std::optional<RecordGuard> guard = guardOf(session);
    m_mirror->put(relative(file), file, guard ? &*guard : nullptr);
}

void Persistence::mirrorRemove(const fs::path& file, const std::string& session) {
    if (!m_mirror) return;
    const std::optional<RecordGuard> guard = guardOf(session);
    m_mirror->remove(relative(file), guard ? &*guard : nullptr);
}

void Persistence::mirrorRemoveTree(const fs::path& dir, const std::string& session) {
    if (!m_mirror) return;
    const std::optional<RecordGuard> guard = guardOf(session);
    m_mirror->removeTree(relative(dir), guard ? &*guard : nullptr);
}

std::optional<RecordGuard> Persistence::guardOf(const std::string& session) {
    if (session.empty()) return std::nullopt;
    std::lock_guard lock(m_stampsMutex);
    const auto it = m_stamps.find(session);
    return RecordGuard{relative(sessionDir(session) / "session.json"), it == m_stamps.end() ? 0 : it->second};
}

void Persistence::knownStamp(const std::string& session, uint64_t stamp) {
    std::lock_guard lock(m_stampsMutex);
    m_stamps[session] = stamp;
}

std::string Persistence::versionFile(int version) { return store::versionFile(version); }

std::string Persistence::writeProblem() const {
    std::error_code ec;
    if (!fs::is_directory(m_dir.root() / "sessions", ec)) return "the data folder '" + m_dir.root().string() + "' has no sessions folder (removed?)";
    try {
        const fs::path probe = m_dir.root() / ".ready-probe";
        store::atomicWrite(probe, "ready\n");
        fs::remove(probe);
        return m_mirror ? m_mirror->writeProblem() : "";
    } catch (const std::exception& e) {
        return e.what();
    }
}

void Persistence::saveSession(Session& s, const std::vector<fs::path>& alsoCommit) {
    const fs::path dir = sessionDir(s.id);
    std::vector<std::pair<std::string, fs::path>> written;
    std::vector<std::pair<int, std::uintmax_t>> stored;
    for (int n : s.volume.versions.unstored()) {
        std::shared_ptr<const core::Volume> older;
        if (n != s.volume.version && !(older = s.volume.versions.inMemory(n))) continue;  // cannot happen: unstored ones stay in memory
        const fs::path vdb = dir / versionFile(n);
        store::atomicWriteWith(vdb, [&](const fs::path& tmp) { core::saveVdb(tmp.string(), n == s.volume.version ? s.volume.current : *older); });
        written.emplace_back(relative(vdb), vdb);
        stored.emplace_back(n, fs::file_size(vdb));
    }
    for (const auto& [n, bytes] : stored) s.volume.versions.markStored(n, bytes);
    for (const auto& file : alsoCommit) written.emplace_back(relative(file), file);
    store::atomicWrite(dir / "session.json", store::encodeSessionRecord(s));
    if (!m_mirror) return;
    store::atomicWrite(dir / "summary.json", store::encodeSessionSummary(s));
    written.emplace_back(relative(dir / "summary.json"), dir / "summary.json");
    try {
        s.storeStamp = m_mirror->putRecord(relative(dir / "session.json"), dir / "session.json", written, s.storeStamp);
        knownStamp(s.id, s.storeStamp);
    } catch (...) {
        s.storeStamp = ~uint64_t(0);  // this copy is not the store's: the next request reads the store's
        throw;
    }
}

std::string Persistence::readVersionFile(const std::string& session, int version, std::uintmax_t expectedBytes) const {
    const fs::path path = sessionDir(session) / versionFile(version);
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) throw IoError("version " + std::to_string(version) + "'s file is missing");
    if (size != expectedBytes)
        throw IoError("version " + std::to_string(version) + "'s file is " + std::to_string(size) + " bytes; it was written with " +
                      std::to_string(expectedBytes));
    std::string bytes = store::readFile(path);
    if (bytes.size() != expectedBytes) throw IoError("version " + std::to_string(version) + "'s file could not be read whole");
    return bytes;
}

core::Volume Persistence::loadVersion(const std::string& session, int version, std::uintmax_t expectedBytes) const {
    return store::loadVersionFile(m_dir, session, version, expectedBytes);
}

void Persistence::quarantineFile(const std::string& session, const std::string& file, const std::string& reason) {
    m_dir.quarantineFile(session, file, reason);
}

std::vector<QuarantineEntry> Persistence::quarantine() const { return m_dir.quarantine(); }

void Persistence::saveViewImage(const std::string& session, const std::string& view, const std::string& kind,
                                const core::Image& image) {
    core::SaveOptions opt;
    opt.halfFloat = false;  // exact
    const fs::path file = sessionDir(session) / "views" / view / (kind + ".exr");
    store::atomicWriteWith(file, [&](const fs::path& tmp) { core::saveImage(tmp.string(), image, opt); });
    mirrorPut(file, session);
}

void Persistence::removeViewImage(const std::string& session, const std::string& view, const std::string& kind) {
    std::error_code ec;
    fs::remove(sessionDir(session) / "views" / view / (kind + ".exr"), ec);
    mirrorRemove(sessionDir(session) / "views" / view / (kind + ".exr"), session);
}

void Persistence::removeView(const std::string& session, const std::string& view) {
    std::error_code ec;
    fs::remove_all(sessionDir(session) / "views" / view, ec);
    mirrorRemoveTree(sessionDir(session) / "views" / view, session);
}

void Persistence::removeSession(const std::string& session) {
    std::error_code ec;
    fs::remove_all(sessionDir(session), ec);
    mirrorRemoveTree(sessionDir(session));
}

void Persistence::removeJob(const std::string& job) {
    std::error_code ec;
    fs::remove(m_dir.jobsDir() / (job + ".json"), ec);
    fs::remove_all(jobFilesDir(job), ec);
    mirrorRemoveTree(jobFilesDir(job));
}

void Persistence::saveJobFiles(const std::string& job) {
    std::error_code ec;
    if (!m_mirror || !fs::is_directory(jobFilesDir(job), ec)) return;
    for (const auto& entry : fs::recursive_directory_iterator(jobFilesDir(job)))
        if (entry.is_regular_file()) mirrorPut(entry.path());
}

bool Persistence::fetchJobFiles(const std::string& job) {
    return m_mirror && m_mirror->materializeTree(relative(jobFilesDir(job)), m_dir.root()) > 0;
}

void Persistence::saveFrame(const std::string& session, int frame, const core::Volume& volume) {
    const fs::path file = sessionDir(session) / "frames" / (std::to_string(frame) + ".vdb");
    store::atomicWriteWith(file, [&](const fs::path& tmp) { core::saveVdb(tmp.string(), volume); });
    mirrorPut(file, session);
}

void Persistence::removeFrame(const std::string& session, int frame) {
    std::error_code ec;
    fs::remove(sessionDir(session) / "frames" / (std::to_string(frame) + ".vdb"), ec);
    mirrorRemove(sessionDir(session) / "frames" / (std::to_string(frame) + ".vdb"), session);
}

void Persistence::saveJob(const Job& job) {
    // With a store, the job queue's row is the record other replicas read (pg_job_queue.cpp).
    store::atomicWrite(m_dir.jobsDir() / (job.id + ".json"), store::encodeJobRecord(job));
}

void Persistence::commitStylizer(Session& s, bool history, uint64_t revision) {
    const fs::path dir = sessionDir(s.id) / "stylizer";
    std::vector<fs::path> files{dir / "scene.json"};
    if (history) {
        store::atomicWrite(dir / "history.json", store::encodeStylizerHistory(s.stylizer.undo, s.stylizer.redo));
        files.push_back(dir / "history.json");
    }
    store::atomicWrite(dir / "scene.json", store::encodeStylizerScene(protocol::stylizerSceneToJson(s.stylizer.scene, s.stylizer.meshRefs), revision));
    if (m_mirror) saveSession(s, files);  // the folder alone: its record is unchanged
}

void Persistence::saveSessionFile(const std::string& session, const std::string& file, const std::string& bytes) {
    store::atomicWrite(sessionDir(session) / file, bytes);
    mirrorPut(sessionDir(session) / file, session);
}

void Persistence::removeSessionFile(const std::string& session, const std::string& file) {
    std::error_code ec;
    fs::remove(sessionDir(session) / file, ec);
    mirrorRemove(sessionDir(session) / file, session);
}

std::vector<std::shared_ptr<Session>> Persistence::loadSessions() {
    std::vector<std::shared_ptr<Session>> out;
    std::vector<fs::path> dirs;
    for (const auto& entry : fs::directory_iterator(m_dir.root() / "sessions"))
        if (entry.is_directory()) dirs.push_back(entry.path());
    for (const auto& dir : dirs) {
        if (!fs::exists(dir / "session.json")) continue;  // a session being created when the server stopped
        try {
            out.push_back(loadSession(dir));
        } catch (const std::exception& e) {
            m_dir.quarantineSession(dir, e.what());
        }
    }
    return out;
}

std::shared_ptr<Session> Persistence::loadSession(const fs::path& dir, uint64_t stamp) {
    size_t recordedDamage = 0;
    std::shared_ptr<Session> s = store::restoreSessionRecord(m_dir, dir, recordedDamage);
    s->storeStamp = stamp;  // what a save below must find in the store (the files' own moment)
    if (m_mirror) knownStamp(s->id, stamp);
    store::restoreStylizerRecord(m_dir, *s, dir, m_readMesh,
                                 [&](const json& scene, uint64_t revision) {
                                     store::atomicWrite(dir / "stylizer" / "scene.json", store::encodeStylizerScene(scene, revision));
                                     mirrorPut(dir / "stylizer" / "scene.json");
                                 });
    if (s->damaged.size() != recordedDamage) saveSession(*s);  // the damage (and any fall-back) is recorded
    return s;
}

std::vector<std::shared_ptr<Job>> Persistence::loadJobs() {
    std::vector<std::shared_ptr<Job>> out;
    // Oldest first: the store's creation order, which pruning follows (each file stat'ed once).
    std::vector<std::pair<fs::file_time_type, fs::directory_entry>> byTime;
    for (const auto& entry : fs::directory_iterator(m_dir.jobsDir())) {
        std::error_code ec;
        byTime.emplace_back(entry.last_write_time(ec), entry);
    }
    std::sort(byTime.begin(), byTime.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [time, entry] : byTime) {
        if (entry.path().extension() != ".json" || store::isUnfinishedWrite(entry.path())) continue;
        try {
            bool interrupted = false;
            auto job = store::decodeJobRecord(store::readFile(entry.path()), interrupted);
            if (interrupted) saveJob(*job);
            out.push_back(job);
        } catch (const std::exception& e) {
            m_dir.quarantineJobRecord(entry.path(), e.what());
        }
    }
    return out;
}

}  // namespace volstyle::server

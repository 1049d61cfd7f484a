#include "server/store/persistence.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/render/environment_lobes.h"
#include "core/stylize/mesh_io.h"
#include "core/volume/vdb_io.h"
#include "protocol/error_body.h"
#include "protocol/render_json.h"
#include "protocol/stylize_json.h"
#include "server/store/data_dir.h"

namespace volstyle::server {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

/// A temporary file a write left behind when the server stopped (store::atomicWrite's names).
bool isUnfinishedWrite(const fs::path& p) { return p.filename().string().find(".tmp-") != std::string::npos; }

std::string readFile(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

/// A view in session.json: the disk's own record (it has kept the API's field names so far, and
/// need not follow the API when it changes).
json viewRecord(const SessionView& v) {
    json j = {{"id", v.id}, {"camera", protocol::cameraToJson(v.camera)}, {"has_target", v.target.has_value()},
              {"has_weights", v.weights.has_value()}, {"has_background", bool(v.background)}};
    if (v.frame) j["frame"] = *v.frame;
    return j;
}

}  // namespace

Persistence::Persistence(fs::path dir, MeshReader readMesh) : m_dir(std::move(dir)), m_readMesh(std::move(readMesh)) {
    std::error_code ec;
    fs::create_directories(m_dir / "sessions", ec);
    fs::create_directories(m_dir / "jobs", ec);
    if (ec) throw IoError("serve: cannot create the data directory '" + m_dir.string() + "': " + ec.message());
}

void Persistence::atomicWrite(const fs::path& path, const std::string& bytes) { store::atomicWrite(path, bytes); }

void Persistence::saveSession(Session& s) {
    const fs::path dir = sessionDir(s.id);
    for (int n : s.versions.unstored()) {
        std::shared_ptr<const core::Volume> older;
        if (n != s.version && !(older = s.versions.inMemory(n))) continue;  // cannot happen: unstored ones stay in memory
        const fs::path vdb = dir / versionFile(n);
        store::atomicWriteWith(vdb, [&](const fs::path& tmp) { core::saveVdb(tmp.string(), n == s.version ? s.volume : *older); });
        s.versions.markStored(n, fs::file_size(vdb));
    }
    json bytes = json::object(), damaged = json::array();
    for (int n : s.versions.numbers())
        if (auto b = s.versions.storedBytes(n)) bytes[std::to_string(n)] = *b;
    for (const auto& d : s.damaged) damaged.push_back({{"file", d.file}, {"reason", d.reason}});
    json views = json::array();
    for (const auto& v : s.views) views.push_back(viewRecord(v));
    json frames = json::array();
    for (const auto& [n, f] : s.frames) frames.push_back({{"frame", n}, {"solved", f.solved}});
    json j = {{"id", s.id}, {"created", s.created}, {"scene", s.scene}, {"version", s.version},
              {"versions", s.versions.numbers()}, {"version_bytes", bytes}, {"damaged", damaged},
              {"lighting", protocol::lightingToJson(s.lighting, s.environmentMap.get())}, {"views", views}, {"next_view", s.nextView}, {"jobs", s.jobs},
              {"frames", frames}};
    atomicWrite(dir / "session.json", protocol::toText(j, 2));
}

std::string Persistence::readVersionFile(const std::string& session, int version, std::uintmax_t expectedBytes) const {
    const fs::path path = sessionDir(session) / versionFile(version);
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) throw IoError("version " + std::to_string(version) + "'s file is missing");
    if (size != expectedBytes)
        throw IoError("version " + std::to_string(version) + "'s file is " + std::to_string(size) + " bytes; it was written with " +
                      std::to_string(expectedBytes));
    std::string bytes = readFile(path);
    if (bytes.size() != expectedBytes) throw IoError("version " + std::to_string(version) + "'s file could not be read whole");
    return bytes;
}

core::Volume Persistence::loadVersion(const std::string& session, int version, std::uintmax_t expectedBytes) const {
    const fs::path path = sessionDir(session) / versionFile(version);
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) throw IoError("version " + std::to_string(version) + "'s file is missing");
    if (expectedBytes && size != expectedBytes)
        throw IoError("version " + std::to_string(version) + "'s file is " + std::to_string(size) + " bytes; it was written with " +
                      std::to_string(expectedBytes));
    return core::loadVdb(path.string());
}

void Persistence::quarantineFile(const std::string& session, const std::string& file, const std::string& reason) {
    const fs::path from = sessionDir(session) / file, to = m_dir / "quarantine" / session / file;
    std::error_code ec;
    fs::create_directories(to.parent_path(), ec);
    if (fs::exists(from)) fs::rename(from, to, ec);
    json r = {{"session", session}, {"file", file}, {"reason", reason}, {"time", isoNow()}};
    atomicWrite(to.string() + ".reason.json", protocol::toText(r, 2));
    spdlog::error("quarantined session {}'s {}: {}", session, file, reason);
}

void Persistence::quarantineSession(const fs::path& dir, const std::string& reason) {
    const std::string session = dir.filename().string();
    const fs::path to = m_dir / "quarantine" / session / "session";
    std::error_code ec;
    fs::create_directories(to.parent_path(), ec);
    fs::remove_all(to, ec);  // an earlier quarantine of the same id
    fs::rename(dir, to, ec);
    if (ec) spdlog::error("restore: cannot move '{}' to the quarantine: {}", dir.string(), ec.message());
    json r = {{"session", session}, {"file", ""}, {"reason", reason}, {"time", isoNow()}};
    atomicWrite(to.string() + ".reason.json", protocol::toText(r, 2));
    spdlog::error("quarantined session {} whole: {}", session, reason);
}

std::vector<QuarantineEntry> Persistence::quarantine() const {
    std::vector<QuarantineEntry> out;
    std::error_code ec;
    const fs::path root = m_dir / "quarantine";
    if (!fs::exists(root, ec)) return out;
    for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (!it->is_regular_file() || !name.ends_with(".reason.json")) continue;
        try {
            json j = json::parse(readFile(it->path()));
            out.push_back({j.at("session"), j.at("file"), j.at("reason"), j.at("time")});
        } catch (const std::exception&) {
            out.push_back({"", fs::relative(it->path(), root).string(), "the reason file is unreadable", ""});
        }
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
    return out;
}

void Persistence::saveViewImage(const std::string& session, const std::string& view, const std::string& kind,
                                const core::Image& image) {
    core::SaveOptions opt;
    opt.halfFloat = false;  // exact
    store::atomicWriteWith(sessionDir(session) / "views" / view / (kind + ".exr"),
                           [&](const fs::path& tmp) { core::saveImage(tmp.string(), image, opt); });
}

void Persistence::removeViewImage(const std::string& session, const std::string& view, const std::string& kind) {
    std::error_code ec;
    fs::remove(sessionDir(session) / "views" / view / (kind + ".exr"), ec);
}

void Persistence::removeView(const std::string& session, const std::string& view) {
    std::error_code ec;
    fs::remove_all(sessionDir(session) / "views" / view, ec);
}

void Persistence::removeSession(const std::string& session) {
    std::error_code ec;
    fs::remove_all(sessionDir(session), ec);
}

void Persistence::removeJob(const std::string& job) {
    std::error_code ec;
    fs::remove(m_dir / "jobs" / (job + ".json"), ec);
    fs::remove_all(jobFilesDir(job), ec);
}

void Persistence::saveFrame(const std::string& session, int frame, const core::Volume& volume) {
    store::atomicWriteWith(sessionDir(session) / "frames" / (std::to_string(frame) + ".vdb"),
                           [&](const fs::path& tmp) { core::saveVdb(tmp.string(), volume); });
}

void Persistence::removeFrame(const std::string& session, int frame) {
    std::error_code ec;
    fs::remove(sessionDir(session) / "frames" / (std::to_string(frame) + ".vdb"), ec);
}

void Persistence::saveJob(const Job& job) { atomicWrite(m_dir / "jobs" / (job.id + ".json"), protocol::toText(job.toJson(), 2)); }

std::vector<std::shared_ptr<Session>> Persistence::loadSessions() {
    std::vector<std::shared_ptr<Session>> out;
    std::vector<fs::path> dirs;
    for (const auto& entry : fs::directory_iterator(m_dir / "sessions"))
        if (entry.is_directory()) dirs.push_back(entry.path());
    for (const auto& dir : dirs) {
        if (!fs::exists(dir / "session.json")) continue;  // a session being created when the server stopped
        try {
            out.push_back(loadSession(dir));
        } catch (const std::exception& e) {
            quarantineSession(dir, e.what());
        }
    }
    return out;
}

std::shared_ptr<Session> Persistence::loadSession(const fs::path& dir) {
    json j;
    try {
        j = json::parse(readFile(dir / "session.json"));
    } catch (const std::exception& e) {
        throw IoError(std::string("session.json is unreadable: ") + e.what());
    }
    auto s = std::make_shared<Session>();
    s->id = j.at("id");
    s->created = j.at("created");
    s->scene = j.at("scene");
    s->nextView = j.at("next_view");
    s->jobs = j.at("jobs").get<std::vector<std::string>>();
    for (const auto& d : j.value("damaged", json::array())) s->damaged.push_back({d.at("file"), d.at("reason")});
    const size_t damagedBefore = s->damaged.size();
    restoreLighting(*s, dir, j.at("lighting"));
    restoreVersions(*s, j);
    for (const auto& v : j.at("views")) {
        SessionView view{v.at("id"), protocol::cameraFromJson(v.at("camera")), std::nullopt, std::nullopt};
        if (v.contains("frame")) view.frame = v.at("frame").get<int>();
        for (const char* kind : {"target", "weights", "background"}) {
            if (!v.value(std::string("has_") + kind, false)) continue;  // "has_background": since 2026-12
            const std::string file = "views/" + view.id + "/" + kind + ".exr";
            try {
                core::Image image = core::loadImage((dir / file).string()).image;
                const std::string k = kind;
                if (k == "background") view.background = std::make_shared<const core::Image>(std::move(image));
                else (k == "target" ? view.target : view.weights) = std::move(image);
            } catch (const std::exception& e) {
                quarantineFile(s->id, file, e.what());  // the view stays, without this image
                s->damaged.push_back({file, e.what()});
            }
        }
        s->views.push_back(std::move(view));
    }
    // The animation's frames (since issue #16): a damaged one is quarantined and dropped.
    for (const auto& f : j.value("frames", json::array())) {
        const int n = f.at("frame").get<int>();
        const std::string file = "frames/" + std::to_string(n) + ".vdb";
        try {
            s->frames[n] = {core::loadVdb((dir / file).string()), f.value("solved", false)};
        } catch (const std::exception& e) {
            quarantineFile(s->id, file, e.what());
            s->damaged.push_back({file, e.what()});
        }
    }
    restoreStylizer(*s, dir);
    if (s->damaged.size() != damagedBefore) saveSession(*s);  // the damage (and any fall-back) is recorded
    return s;
}

void Persistence::saveStylizerScene(const std::string& session, const json& scene, uint64_t revision) {
    fs::create_directories(sessionDir(session) / "stylizer");
    atomicWrite(sessionDir(session) / "stylizer" / "scene.json", protocol::toText({{"revision", revision}, {"scene", scene}}, 2));
}

void Persistence::saveStylizerHistory(const std::string& session, const json& undo, const json& redo) {
    fs::create_directories(sessionDir(session) / "stylizer");
    atomicWrite(sessionDir(session) / "stylizer" / "history.json", protocol::toText({{"undo", undo}, {"redo", redo}}));
}

void Persistence::saveSessionFile(const std::string& session, const std::string& file, const std::string& bytes) {
    const fs::path path = sessionDir(session) / file;
    fs::create_directories(path.parent_path());
    atomicWrite(path, bytes);
}

void Persistence::removeSessionFile(const std::string& session, const std::string& file) {
    std::error_code ec;
    fs::remove(sessionDir(session) / file, ec);
}

void Persistence::restoreLighting(Session& s, const fs::path& dir, const json& lighting) {
    const std::string file = "environment.image";
    if (fs::exists(dir / file)) {
        try {
            const std::string bytes = readFile(dir / file);
            auto map = std::make_shared<core::Image>(core::loadImageFromMemory(bytes.data(), bytes.size(), "the environment map").image);
            if (std::string why = core::latLongMapProblem(*map); !why.empty()) throw IoError(why);
            s.environmentMap = std::move(map);
        } catch (const std::exception& e) {
            quarantineFile(s.id, file, e.what());
            s.damaged.push_back({file, e.what()});
        }
    }
    protocol::LightingRequest request = protocol::lightingFromJson(lighting);
    if (!s.environmentMap) {  // damaged: the background's colour, and the lobes' radiances as they were
        request.backgroundUsesSessionMap = request.environmentUsesSessionMap = false;
    }
    s.lighting = request.resolve(s.environmentMap);
}

void Persistence::restoreStylizer(Session& s, const fs::path& dir) {
    const auto damage = [&](const std::string& file, const std::string& reason) {
        quarantineFile(s.id, file, reason);
        s.damaged.push_back({file, reason});
    };
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(dir / "stylizer" / "occluders", ec)) {
        const std::string file = "stylizer/occluders/" + entry.path().filename().string();
        const std::string format = entry.path().extension().string().substr(entry.path().extension().empty() ? 0 : 1);
        if (isUnfinishedWrite(entry.path())) continue;  // an unfinished write (atomicWrite's temporary)
        try {
            const std::string bytes = readFile(entry.path());
            auto mesh = std::make_shared<const core::Mesh>(m_readMesh ? m_readMesh(bytes, format) : core::loadMeshFromMemory(bytes, format));
            s.stylizer.meshes[entry.path().stem().string()] = {format, std::move(mesh), bytes.size()};
        } catch (const std::exception& e) {
            damage(file, e.what());
        }
    }
    if (fs::exists(dir / "stylizer" / "tf.image")) {
        try {
            const std::string bytes = readFile(dir / "stylizer" / "tf.image");
            s.stylizer.transferImage =
                std::make_shared<const core::Image>(core::loadImageFromMemory(bytes.data(), bytes.size(), "the transfer function", 4096).image);
        } catch (const std::exception& e) {
            damage("stylizer/tf.image", e.what());
        }
    }
    if (fs::exists(dir / "stylizer" / "history.json")) {  // a convenience: an unreadable one is dropped, not the scene
        try {
            const json h = json::parse(readFile(dir / "stylizer" / "history.json"));
            for (const json& scene : h.at("undo")) s.stylizer.undo.push_back(scene);
            for (const json& scene : h.at("redo")) s.stylizer.redo.push_back(scene);
        } catch (const std::exception& e) {
            s.stylizer.undo.clear(), s.stylizer.redo.clear();
            spdlog::warn("session {}: the stylizer's undo history is unreadable and was dropped: {}", s.id, e.what());
        }
    }
    if (!fs::exists(dir / "stylizer" / "scene.json")) return;  // never edited: builtin:forest
    protocol::StylizerSceneRequest request;
    try {
        const json j = json::parse(readFile(dir / "stylizer" / "scene.json"));
        request = protocol::stylizerSceneFromJson(j.at("scene"), "", protocol::SceneSource::Api);
        s.stylizer.revision = j.at("revision").get<uint64_t>();

    } catch (const std::exception& e) {
        damage("stylizer/scene.json", std::string("the stylizer's scene is unreadable (it is builtin:forest again): ") + e.what());
        return;
    }
    // What a damaged upload held is lost, and only that: its occluders, or the TF.
    std::vector<std::string> lost;
    for (size_t i = request.meshRefs.size(); i-- > 0;)
        if (!protocol::builtinMesh(request.meshRefs[i]) && !s.stylizer.meshes.contains(request.meshRefs[i])) {
            lost.push_back("occluder '" + request.scene.occluders[i].name + "' (mesh '" + request.meshRefs[i] + "')");
            request.meshRefs.erase(request.meshRefs.begin() + std::ptrdiff_t(i));
            request.scene.occluders.erase(request.scene.occluders.begin() + std::ptrdiff_t(i));
        }
    if (!request.tfImages.empty() && !s.stylizer.transferImage) {  // the TFs that showed the image go
        bool scene = false, keys = false;
        for (const auto& ref : request.tfImages) (ref.key < 0 ? scene : keys) = true;
        if (scene) lost.push_back("the transfer function"), request.scene.transferFunction.reset();
        if (keys) {
            lost.push_back("the key frames' transfer functions");
            for (auto& k : request.scene.keyframes) k.transferFunction.reset();
        }
        request.tfImages.clear();
    }
    try {
        s.stylizer.scene = resolveStylizerScene(s.stylizer, request);
        s.stylizer.meshRefs = request.meshRefs;
    } catch (const std::exception& e) {
        damage("stylizer/scene.json", std::string("the stylizer's scene no longer loads (it is builtin:forest again): ") + e.what());
        return;
    }
    if (!lost.empty()) {
        std::string what;
        for (const auto& l : lost) what += (what.empty() ? "" : ", ") + l;
        s.damaged.push_back({"stylizer/scene.json", "its uploads were damaged; the scene lost " + what});
        spdlog::error("session {}'s stylizer scene lost {}", s.id, what);
        saveStylizerScene(s.id, protocol::stylizerSceneToJson(s.stylizer.scene, s.stylizer.meshRefs), ++s.stylizer.revision);
    }
}

void Persistence::restoreVersions(Session& s, const json& j) {
    const json bytes = j.value("version_bytes", json::object());
    for (int n : j.at("versions")) s.versions.add(n);
    for (const auto& d : s.damaged)  // damage found before a restart stays listed
        for (int n : s.versions.numbers())
            if (d.file == versionFile(n)) s.versions.markDamaged(n, d.reason);
    const auto damage = [&](int n, const std::string& reason) {
        quarantineFile(s.id, versionFile(n), reason);
        s.versions.markDamaged(n, reason);
        s.damaged.push_back({versionFile(n), reason});
    };
    // Every version's file must exist with the size it was written with (a stat, not a read).
    for (int n : s.versions.numbers()) {
        if (s.versions.damage(n)) continue;
        std::error_code ec;
        const std::uintmax_t size = fs::file_size(sessionDir(s.id) / versionFile(n), ec);
        const std::uintmax_t expected = bytes.contains(std::to_string(n)) ? bytes[std::to_string(n)].get<std::uintmax_t>() : size;
        if (ec) damage(n, "the file is missing");
        else if (size != expected) damage(n, "the file is " + std::to_string(size) + " bytes; it was written with " + std::to_string(expected));
        else s.versions.markStored(n, size);
    }
    // The current version is read now; if it is damaged, the newest readable one becomes current.
    const int recorded = j.at("version");
    for (auto it = s.versions.numbers().rbegin(); it != s.versions.numbers().rend(); ++it) {
        const int n = *it;
        if (n > recorded || s.versions.damage(n)) continue;
        try {
            s.volume = loadVersion(s.id, n, *s.versions.storedBytes(n));
            s.version = n;
            if (n != recorded) spdlog::warn("restore: session {} falls back from version {} to {}", s.id, recorded, n);
            return;
        } catch (const std::exception& e) {
            damage(n, e.what());
        }
    }
    throw IoError("no version of the volume is readable");
}

std::vector<std::shared_ptr<Job>> Persistence::loadJobs() {
    std::vector<std::shared_ptr<Job>> out;
    // Oldest first: the store's creation order, which pruning follows (each file stat'ed once).
    std::vector<std::pair<fs::file_time_type, fs::directory_entry>> byTime;
    for (const auto& entry : fs::directory_iterator(m_dir / "jobs")) {
        std::error_code ec;
        byTime.emplace_back(entry.last_write_time(ec), entry);
    }
    std::sort(byTime.begin(), byTime.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<fs::directory_entry> entries;
    for (auto& [time, entry] : byTime) entries.push_back(std::move(entry));
    for (const auto& entry : entries) {
        if (entry.path().extension() != ".json" || isUnfinishedWrite(entry.path())) continue;
        try {
            json j = json::parse(readFile(entry.path()));
            auto job = std::make_shared<Job>();
            job->id = j["id"];
            job->session = j["session"];
            const std::string state = j["state"];
            job->state = protocol::jobStateFromName(state).value_or(protocol::JobState::Running);
            job->progress = j["progress"];
            job->result = j["result"];
            job->error = j["error"];
            if (!job->isFinished()) {
                job->fail(protocol::JobState::Failed, protocol::ErrorCode::Interrupted,
                          "the server stopped while this job was " + state + "; the volume keeps its last committed version");
                saveJob(*job);
            }
            job->events.emplace_back(protocol::finalEvent(job->state), job->toJson());
            out.push_back(job);
        } catch (const std::exception& e) {
            // Out of the way, with its reason: a job record holds no work to lose.
            const std::string file = entry.path().filename().string();
            const fs::path to = m_dir / "quarantine" / "jobs" / file;
            std::error_code ec;
            fs::create_directories(to.parent_path(), ec);
            fs::rename(entry.path(), to, ec);
            json r = {{"session", ""}, {"file", "jobs/" + file}, {"reason", e.what()}, {"time", isoNow()}};
            atomicWrite(to.string() + ".reason.json", protocol::toText(r, 2));
            spdlog::error("restore: quarantined job record '{}': {}", file, e.what());
        }
    }
    return out;
}

}  // namespace volstyle::server

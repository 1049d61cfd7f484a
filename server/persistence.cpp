#include "server/persistence.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/volume/vdb_io.h"
#include "protocol/error_body.h"
#include "protocol/render_json.h"

namespace volstyle::server {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

/// Flushes a written file to disk before it is renamed into place.
void syncFile(const fs::path& p) {
    int fd = ::open(p.c_str(), O_RDONLY);
    if (fd >= 0) {
        ::fsync(fd);
        ::close(fd);
    }
}

std::string readFile(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

}  // namespace

Persistence::Persistence(fs::path dir) : m_dir(std::move(dir)) {
    std::error_code ec;
    fs::create_directories(m_dir / "sessions", ec);
    fs::create_directories(m_dir / "jobs", ec);
    if (ec) throw IoError("serve: cannot create the data directory '" + m_dir.string() + "': " + ec.message());
}

void Persistence::atomicWrite(const fs::path& path, const std::string& bytes) {
    fs::create_directories(path.parent_path());
    const fs::path tmp = path.string() + ".tmp-" + SessionStore::newId().substr(0, 8);
    int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) throw IoError("cannot write '" + tmp.string() + "'");
    size_t done = 0;
    while (done < bytes.size()) {
        ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n <= 0) {
            ::close(fd);
            fs::remove(tmp);
            throw IoError("cannot write '" + tmp.string() + "' (disk full?)");
        }
        done += size_t(n);
    }
    ::fsync(fd);
    ::close(fd);
    fs::rename(tmp, path);
}

void Persistence::saveSession(const Session& s) {
    const fs::path dir = sessionDir(s.id);
    json versions = json::array();
    for (const auto& [n, volume] : s.versions) {
        versions.push_back(n);
        const fs::path vdb = dir / "versions" / (std::to_string(n) + ".vdb");
        if (!fs::exists(vdb)) {
            fs::create_directories(vdb.parent_path());
            const fs::path tmp = vdb.string() + ".tmp.vdb";
            core::saveVdb(tmp.string(), volume);
            syncFile(tmp);
            fs::rename(tmp, vdb);
        }
    }
    json views = json::array();
    for (const auto& v : s.views)
        views.push_back({{"id", v.id}, {"camera", protocol::cameraToJson(v.camera)}, {"has_target", v.target.has_value()},
                         {"has_weights", v.weights.has_value()}});
    json j = {{"id", s.id}, {"created", s.created}, {"scene", s.scene}, {"version", s.version}, {"versions", versions},
              {"lighting", protocol::lightingToJson(s.lighting)}, {"views", views}, {"next_view", s.nextView}, {"jobs", s.jobs}};
    atomicWrite(dir / "session.json", protocol::toText(j, 2));
}

void Persistence::saveViewImage(const std::string& session, const std::string& view, const std::string& kind,
                                const core::Image& image) {
    const fs::path dir = sessionDir(session) / "views" / view;
    fs::create_directories(dir);
    const fs::path tmp = dir / (kind + ".tmp.exr"), path = dir / (kind + ".exr");
    core::SaveOptions opt;
    opt.halfFloat = false;  // exact
    core::saveImage(tmp.string(), image, opt);
    syncFile(tmp);
    fs::rename(tmp, path);
}

void Persistence::removeView(const std::string& session, const std::string& view) {
    std::error_code ec;
    fs::remove_all(sessionDir(session) / "views" / view, ec);
}

void Persistence::removeSession(const std::string& session) {
    std::error_code ec;
    fs::remove_all(sessionDir(session), ec);
}

void Persistence::saveJob(const Job& job) { atomicWrite(m_dir / "jobs" / (job.id + ".json"), protocol::toText(job.toJson(), 2)); }

std::vector<std::shared_ptr<Session>> Persistence::loadSessions() {
    std::vector<std::shared_ptr<Session>> out;
    for (const auto& entry : fs::directory_iterator(m_dir / "sessions")) {
        const fs::path file = entry.path() / "session.json";
        if (!fs::exists(file)) continue;
        try {
            json j = json::parse(readFile(file));
            auto s = std::make_shared<Session>();
            s->id = j["id"];
            s->created = j["created"];
            s->scene = j["scene"];
            s->version = j["version"];
            s->nextView = j["next_view"];
            s->jobs = j["jobs"].get<std::vector<std::string>>();
            s->lighting = protocol::lightingFromJson(j["lighting"]).lighting;
            for (int n : j["versions"])
                s->versions[n] = core::loadVdb((entry.path() / "versions" / (std::to_string(n) + ".vdb")).string());
            s->volume = s->versions.at(s->version);
            for (const auto& v : j["views"]) {
                SessionView view{v["id"], protocol::cameraFromJson(v["camera"]), std::nullopt, std::nullopt};
                const fs::path dir = entry.path() / "views" / view.id;
                if (v["has_target"].get<bool>()) view.target = core::loadImage((dir / "target.exr").string()).image;
                if (v["has_weights"].get<bool>()) view.weights = core::loadImage((dir / "weights.exr").string()).image;
                s->views.push_back(std::move(view));
            }
            out.push_back(s);
        } catch (const std::exception& e) {
            spdlog::error("restore: skipping session '{}': {}", entry.path().filename().string(), e.what());
        }
    }
    return out;
}

std::vector<std::shared_ptr<Job>> Persistence::loadJobs() {
    std::vector<std::shared_ptr<Job>> out;
    for (const auto& entry : fs::directory_iterator(m_dir / "jobs")) {
        if (entry.path().extension() != ".json") continue;
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
            spdlog::error("restore: skipping job '{}': {}", entry.path().filename().string(), e.what());
        }
    }
    return out;
}

}  // namespace volstyle::server

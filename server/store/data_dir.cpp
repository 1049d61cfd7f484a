#include "server/store/data_dir.h"

#include <fcntl.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>

#include "core/base/errors.h"
#include "protocol/validation.h"
#include "server/state/session_store.h"

namespace volstyle::server::store {
namespace {

namespace fs = std::filesystem;

std::string why(const std::string& step, const fs::path& p) { return "cannot " + step + " '" + p.string() + "': " + std::strerror(errno); }

/// fsync of a file or folder; IoError naming `step` on failure.
void syncPath(const fs::path& p, int flags, const std::string& step) {
    const int fd = ::open(p.c_str(), flags | O_CLOEXEC);
    if (fd < 0) throw IoError(why("open for " + step, p));
    const int rc = ::fsync(fd);
    const int saved = errno;
    ::close(fd);
    errno = saved;
    if (rc != 0) throw IoError(why(step, p));
}

/// `path`'s temporary sibling: the name and a random tag ("session.json.tmp-1a2b3c4d"), and with
/// `keepExtension` the extension again ("1.vdb.tmp-1a2b3c4d.vdb"). Restores skip ".tmp-" names.
fs::path temporaryFor(const fs::path& path, bool keepExtension) {
    static std::atomic<uint64_t> counter{std::random_device{}()};
    char tag[17];
    std::snprintf(tag, sizeof tag, "%08llx", static_cast<unsigned long long>(++counter & 0xffffffffull));
    return path.parent_path() / (path.filename().string() + ".tmp-" + tag + (keepExtension ? path.extension().string() : ""));
}

void writeThrough(const fs::path& path, bool keepExtension, const std::function<void(const fs::path& tmp)>& write);

void renameInto(const fs::path& tmp, const fs::path& path) {
    if (::rename(tmp.c_str(), path.c_str()) != 0) {
        const std::string message = why("rename into", path);
        std::error_code ec;
        fs::remove(tmp, ec);
        throw IoError(message);
    }
    syncFolder(path.parent_path());
}

}  // namespace

void syncFolder(const fs::path& dir) { syncPath(dir.empty() ? fs::path(".") : dir, O_RDONLY | O_DIRECTORY, "fsync the folder"); }

void atomicWrite(const fs::path& path, const std::string& bytes) {
    writeThrough(path, false, [&](const fs::path& tmp) {
        const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd < 0) throw IoError(why("write", tmp));
        for (size_t done = 0; done < bytes.size();) {
            const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                const std::string message = why("write", tmp) + " (disk full?)";
                ::close(fd);
                throw IoError(message);
            }
            done += size_t(n);
        }
        if (::close(fd) != 0) throw IoError(why("close", tmp));
    });
}

void atomicWriteWith(const fs::path& path, const std::function<void(const fs::path& tmp)>& write) {
    writeThrough(path, true, write);
}

namespace {

/// Creates `dir` and the folders above it that are missing, each made durable: a new folder's
/// entry lives in its parent, so the parent is fsynced after it (top down).
void createFolders(const fs::path& dir) {
    std::vector<fs::path> missing;
    std::error_code ec;
    for (fs::path d = dir; !d.empty() && !fs::exists(d, ec); d = d.parent_path()) {
        missing.push_back(d);
        if (d == d.parent_path()) break;
    }
    if (missing.empty()) return;
    fs::create_directories(dir, ec);
    if (ec) throw IoError("cannot create the folder '" + dir.string() + "': " + ec.message());
    for (auto it = missing.rbegin(); it != missing.rend(); ++it) syncFolder(it->parent_path());
}

void writeThrough(const fs::path& path, bool keepExtension, const std::function<void(const fs::path& tmp)>& write) {
    createFolders(path.parent_path());
    const fs::path tmp = temporaryFor(path, keepExtension);
    try {
        write(tmp);
        syncPath(tmp, O_RDONLY, "fsync");
    } catch (...) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw;
    }
    renameInto(tmp, path);
}

}  // namespace

void durableRename(const fs::path& from, const fs::path& to) {
    if (::rename(from.c_str(), to.c_str()) != 0) throw IoError(why("move '" + from.string() + "' to", to));
    syncFolder(to.parent_path());
    if (from.parent_path() != to.parent_path()) syncFolder(from.parent_path());
}

bool isUnfinishedWrite(const fs::path& p) { return p.filename().string().find(".tmp-") != std::string::npos; }

std::string readFile(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

DataDir::DataDir(fs::path root) : m_root(std::move(root)) {
    try {
        createFolders(m_root / "sessions");
        createFolders(m_root / "jobs");
    } catch (const IoError& e) {
        throw IoError("serve: cannot create the data directory '" + m_root.string() + "': " + e.what());
    }
}

void DataDir::writeReason(const fs::path& to, const std::string& session, const std::string& file, const std::string& reason) {
    const nlohmann::json r = {{"session", session}, {"file", file}, {"reason", reason}, {"time", isoNow()}};
    atomicWrite(to.string() + ".reason.json", protocol::toText(r, 2));
}

void DataDir::quarantineFile(const std::string& session, const std::string& file, const std::string& reason) {
    const fs::path from = sessionDir(session) / file, to = m_root / "quarantine" / session / file;
    std::error_code ec;
    fs::create_directories(to.parent_path(), ec);
    if (fs::exists(from)) fs::rename(from, to, ec);
    writeReason(to, session, file, reason);
    spdlog::error("quarantined session {}'s {}: {}", session, file, reason);
}

void DataDir::quarantineSession(const fs::path& dir, const std::string& reason) {
    const std::string session = dir.filename().string();
    const fs::path to = m_root / "quarantine" / session / "session";
    std::error_code ec;
    fs::create_directories(to.parent_path(), ec);
    fs::remove_all(to, ec);  // an earlier quarantine of the same id
    fs::rename(dir, to, ec);
    if (ec) spdlog::error("restore: cannot move '{}' to the quarantine: {}", dir.string(), ec.message());
    writeReason(to, session, "", reason);
    spdlog::error("quarantined session {} whole: {}", session, reason);
}

void DataDir::quarantineJobRecord(const fs::path& record, const std::string& reason) {
    // Out of the way, with its reason: a job record holds no work to lose.
    const std::string file = record.filename().string();
    const fs::path to = m_root / "quarantine" / "jobs" / file;
    std::error_code ec;
    fs::create_directories(to.parent_path(), ec);
    fs::rename(record, to, ec);
    writeReason(to, "", "jobs/" + file, reason);
    spdlog::error("restore: quarantined job record '{}': {}", file, reason);
}

std::vector<QuarantineEntry> DataDir::quarantine() const {
    std::vector<QuarantineEntry> out;
    std::error_code ec;
    const fs::path root = m_root / "quarantine";
    if (!fs::exists(root, ec)) return out;
    for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (!it->is_regular_file() || !name.ends_with(".reason.json")) continue;
        try {
            const nlohmann::json j = nlohmann::json::parse(readFile(it->path()));
            out.push_back({j.at("session"), j.at("file"), j.at("reason"), j.at("time")});
        } catch (const std::exception&) {
            out.push_back({"", fs::relative(it->path(), root).string(), "the reason file is unreadable", ""});
        }
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
    return out;
}

}  // namespace volstyle::server::store

#include "server/store/data_dir.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <random>

#include "core/base/errors.h"

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

void writeThrough(const fs::path& path, bool keepExtension, const std::function<void(const fs::path& tmp)>& write) {
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    if (ec) throw IoError("cannot create the folder '" + path.parent_path().string() + "': " + ec.message());
    const fs::path tmp = temporaryFor(path, keepExtension);
    try {
        write(tmp);
        syncPath(tmp, O_RDONLY, "fsync");
    } catch (...) {
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

}  // namespace volstyle::server::store

// A session's volume versions (session_service.h): committing and reverting versions, edits baked
// into a new version (perturbation, refraction), VDB uploads (read first in the child reader) and
// downloads.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/base/errors.h"
#include "core/render/gpu_volume.h"
#include "core/translucent/perturbation.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"
#include "server/store/persistence.h"
#include "server/service/session_service.h"
#include "server/runtime/vdb_reader.h"

namespace volstyle::server {
namespace {

using protocol::ApiError;
using protocol::ErrorCode;

/// A private temporary file, removed when this goes out of scope (OpenVDB reads and writes files).
struct TempVdb {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("volstyle-" + SessionStore::newId() + ".vdb");
    ~TempVdb() {
        std::error_code ec;
        std::filesystem::remove(path, ec);
    }
};

}  // namespace

std::shared_ptr<core::GpuVolume> SessionService::commitVersion(Session& s, core::Volume volume) {
    const int n = s.versions.newest() + 1;  // after damaged ones too: numbers are never reused
    s.versions.retire(s.version, std::move(s.volume));
    s.volume = std::move(volume);
    s.version = n;
    s.versions.add(n);
    saved(s);
    if (s.stylizer.scene.volume) stylizerChanged(s);  // its medium is the session's volume: live frames follow
    return std::move(s.gpu);
}

void SessionService::checkVersion(const Session& s, int n) const {
    if (!s.versions.has(n)) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' has no version " + std::to_string(n));
    if (auto reason = s.versions.damage(n))
        throw ApiError(ErrorCode::IoError, "version " + std::to_string(n) + " of session '" + s.id +
                                               "' is damaged and was quarantined (" + *reason + "); choose another version");
}

void SessionService::recordDamage(Session& s, int n, const std::string& reason) {
    std::lock_guard lock(s.mutex);
    if (s.removed || s.versions.damage(n)) return;
    const std::string file = Persistence::versionFile(n);
    m_persist->quarantineFile(s.id, file, reason);
    s.versions.markDamaged(n, reason);
    s.damaged.push_back({file, reason});
    saved(s);
}

core::Volume SessionService::olderVersion(Session& s, int n) {
    std::uintmax_t bytes = 0;
    {
        std::lock_guard lock(s.mutex);
        checkVersion(s, n);
        if (n == s.version) return s.volume;
        if (auto v = s.versions.inMemory(n)) return *v;
        bytes = s.versions.storedBytes(n).value_or(0);
    }
    // Read from disk without the lock (a 256³ version takes a second).
    core::Volume v;
    try {
        v = m_persist->loadVersion(s.id, n, bytes);
    } catch (const Error& e) {
        recordDamage(s, n, e.what());
        checkVersion(s, n);  // io_error, or not_found if the session went meanwhile
        throw;
    }
    std::lock_guard lock(s.mutex);
    s.versions.remember(n, v);
    return v;
}

std::vector<QuarantineEntry> SessionService::quarantine() const {
    return m_persist ? m_persist->quarantine() : std::vector<QuarantineEntry>{};
}

void SessionService::release(std::shared_ptr<core::GpuVolume> gpu) {
    if (gpu) m_gl->run([gpu = std::move(gpu)](core::GpuDevice&) mutable { gpu.reset(); });
}

int SessionService::revert(Session& s, int version) {
    core::Volume old = olderVersion(s, version);
    std::shared_ptr<core::GpuVolume> stale;
    int now = 0;
    {
        std::lock_guard lock(s.mutex);
        m_memory.check(s, old.memoryBytes(), 0, "reverting to version " + std::to_string(version));
        stale = commitVersion(s, std::move(old));  // undo is a new version with the old content: nothing is lost
        now = s.version;
    }
    release(std::move(stale));
    return now;
}

int SessionService::editVolume(Session& s, const std::function<void(core::Volume&)>& edit) {
    core::Volume volume;
    int base = 0;
    {
        std::lock_guard lock(s.mutex);
        volume = s.volume;
        base = s.version;
    }
    edit(volume);  // off the lock: O(voxels)
    if (m_volumeEditHook) m_volumeEditHook();
    std::shared_ptr<core::GpuVolume> stale;
    int now = 0;
    {
        std::lock_guard lock(s.mutex);
        // Another change committed while this edit ran off the lock: committing the copy would
        // silently drop that change (a lost update), so the stale edit is refused instead.
        if (s.version != base)
            throw ApiError(ErrorCode::Busy, "the volume changed (version " + std::to_string(base) + " → " + std::to_string(s.version) +
                                                ") while this edit ran; send it again to apply it to version " + std::to_string(s.version));
        m_memory.check(s, volume.memoryBytes(), 0, "the edited volume");
        stale = commitVersion(s, std::move(volume));
        now = s.version;
    }
    release(std::move(stale));
    return now;
}

int SessionService::perturb(Session& s, const core::Perturbation& perturbation) {
    return editVolume(s, [&](core::Volume& v) { v = core::perturbVolume(v, perturbation); });
}

int SessionService::setRefraction(Session& s, const std::optional<core::GlassSphere>& glass) {
    return editVolume(s, [&](core::Volume& v) {
        if (glass) {
            core::addGlassSphere(v, *glass);
        } else {
            if (!v.refractiveIndex()) throw ApiError(ErrorCode::InvalidArgument, "the volume has no refractive_index grid to remove");
            v.refractiveIndex().reset();
        }
    });
}

void SessionService::uploadVdb(Session& s, const std::string& bytes) {
    core::Volume v = readUploadedVdb(bytes);
    std::shared_ptr<core::GpuVolume> stale;
    {
        std::lock_guard lock(s.mutex);
        m_memory.check(s, v.memoryBytes(), 0, "the uploaded volume");
        s.scene = "upload";  // the session no longer shows its first scene (saved with the version)
        stale = commitVersion(s, std::move(v));
    }
    release(std::move(stale));
}

core::Volume SessionService::readUploadedVdb(const std::string& bytes) const {
    return readUpload<core::Volume>(bytes, [this](const std::string& path) { return loadUntrustedVdb(path, m_limits.volumeLimits, m_limits.vdbReader); });
}

std::map<int, core::Volume> SessionService::readUploadedVdbFrames(const std::string& bytes) const {
    return readUpload<std::map<int, core::Volume>>(
        bytes, [this](const std::string& path) { return loadUntrustedVdbFrames(path, m_limits.volumeLimits, m_limits.vdbReader); });
}

template <typename T>
T SessionService::readUpload(const std::string& bytes, const std::function<T(const std::string&)>& read) const {
    checkUploadSize(bytes, "the VDB");
    TempVdb tmp;
    std::ofstream(tmp.path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    T v;
    try {
        v = read(tmp.path.string());
    } catch (const Error& e) {
        std::string msg = e.what();
        for (const std::string& path : {"'" + tmp.path.string() + "'", tmp.path.string()})
            for (size_t pos; (pos = msg.find(path)) != std::string::npos;) msg.replace(pos, path.size(), "the upload");
        throw ApiError(dynamic_cast<const LimitExceeded*>(&e) ? ErrorCode::TooLarge : ErrorCode::UnsupportedMedia, msg);
    }
    return v;
}

std::string SessionService::downloadVdb(Session& s, std::optional<int> version) {
    int n = 0;
    std::optional<std::uintmax_t> stored;
    {
        std::lock_guard lock(s.mutex);
        n = version.value_or(s.version);
        checkVersion(s, n);
        if (m_persist) stored = s.versions.storedBytes(n);
    }
    if (stored) {  // the file as written: no decode, no encode
        try {
            return m_persist->readVersionFile(s.id, n, *stored);
        } catch (const Error& e) {
            recordDamage(s, n, e.what());
            checkVersion(s, n);
            throw;
        }
    }
    return vdbBytes(olderVersion(s, n));
}

std::string SessionService::vdbBytes(const core::Volume& v) {
    TempVdb tmp;
    core::saveVdb(tmp.path.string(), v);
    std::ifstream f(tmp.path, std::ios::binary);
    std::stringstream bytes;
    bytes << f.rdbuf();
    return bytes.str();
}

}  // namespace volstyle::server

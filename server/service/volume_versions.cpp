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
#include "server/service/services.h"
#include "server/runtime/vdb_reader.h"

namespace volstyle::server {
namespace {

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

void VolumeService::checkVersion(const Session& s, int n) const {
    if (!s.volume.versions.has(n)) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' has no version " + std::to_string(n));
    if (auto reason = s.volume.versions.damage(n))
        throw ApiError(ErrorCode::IoError, "version " + std::to_string(n) + " of session '" + s.id +
                                               "' is damaged and was quarantined (" + *reason + "); choose another version");
}

void VolumeService::recordDamage(Session& s, int n, const std::string& reason) {
    std::lock_guard lock(s.mutex);
    if (s.removed || s.volume.versions.damage(n)) return;
    const std::string file = Persistence::versionFile(n);
    m_ctx.persist->quarantineFile(s.id, file, reason);
    s.volume.versions.markDamaged(n, reason);
    s.damaged.push_back({file, reason});
    m_ctx.saved(s);
}

core::Volume VolumeService::olderVersion(Session& s, int n) {
    std::uintmax_t bytes = 0;
    {
        std::lock_guard lock(s.mutex);
        checkVersion(s, n);
        if (n == s.volume.version) return s.volume.current;
        if (auto v = s.volume.versions.inMemory(n)) return *v;
        bytes = s.volume.versions.storedBytes(n).value_or(0);
    }
    // Read from disk without the lock (a 256³ version takes a second).
    core::Volume v;
    try {
        v = m_ctx.persist->loadVersion(s.id, n, bytes);
    } catch (const Error& e) {
        recordDamage(s, n, e.what());
        checkVersion(s, n);  // io_error, or not_found if the session went meanwhile
        throw;
    }
    std::lock_guard lock(s.mutex);
    s.volume.versions.remember(n, v);
    return v;
}

int VolumeService::revert(Session& s, int version) {
    core::Volume old = olderVersion(s, version);
    std::shared_ptr<core::GpuVolume> stale;
    int now = 0;
    {
        std::lock_guard lock(s.mutex);
        m_ctx.memory.check(s, old.memoryBytes(), 0, "reverting to version " + std::to_string(version));
        stale = m_ctx.commitVersion(s, std::move(old), version);  // a new version with the old content: nothing is lost
        now = s.volume.version;
    }
    m_ctx.release(std::move(stale));
    return now;
}

int VolumeService::step(Session& s, bool redo) {
    int target = 0;
    {
        std::lock_guard lock(s.mutex);
        const std::vector<int>& from = redo ? s.volume.redo : s.volume.undo;
        if (from.empty()) throw ApiError(ErrorCode::Busy, redo ? "nothing to redo" : "nothing to undo");
        target = from.back();
    }
    core::Volume old = olderVersion(s, target);  // off the lock: a stored version is read from disk
    std::shared_ptr<core::GpuVolume> stale;
    int now = 0;
    {
        std::lock_guard lock(s.mutex);
        std::vector<int>& from = redo ? s.volume.redo : s.volume.undo;
        std::vector<int>& to = redo ? s.volume.undo : s.volume.redo;
        if (from.empty() || from.back() != target)  // another step or an edit came first
            throw ApiError(ErrorCode::Busy, "the volume changed meanwhile; look at the session and step again");
        m_ctx.memory.check(s, old.memoryBytes(), 0, std::string(redo ? "redoing" : "undoing") + " to version " + std::to_string(target));
        from.pop_back();
        to.push_back(s.volume.shows);
        stale = m_ctx.commitStep(s, std::move(old), target);
        now = s.volume.version;
    }
    m_ctx.release(std::move(stale));
    return now;
}

int VolumeService::editVolume(Session& s, const std::function<void(core::Volume&)>& edit) {
    core::Volume volume;
    int base = 0;
    {
        std::lock_guard lock(s.mutex);
        volume = s.volume.current;
        base = s.volume.version;
    }
    edit(volume);  // off the lock: O(voxels)
    if (m_volumeEditHook) m_volumeEditHook();
    std::shared_ptr<core::GpuVolume> stale;
    int now = 0;
    {
        std::lock_guard lock(s.mutex);
        // Another change committed while this edit ran off the lock: committing the copy would
        // silently drop that change (a lost update), so the stale edit is refused instead.
        if (s.volume.version != base)
            throw ApiError(ErrorCode::Busy, "the volume changed (version " + std::to_string(base) + " → " + std::to_string(s.volume.version) +
                                                ") while this edit ran; send it again to apply it to version " + std::to_string(s.volume.version));
        m_ctx.memory.check(s, volume.memoryBytes(), 0, "the edited volume");
        stale = m_ctx.commitVersion(s, std::move(volume));
        now = s.volume.version;
    }
    m_ctx.release(std::move(stale));
    return now;
}

int VolumeService::perturb(Session& s, const core::Perturbation& perturbation) {
    return editVolume(s, [&](core::Volume& v) { v = core::perturbVolume(v, perturbation); });
}

int VolumeService::setRefraction(Session& s, const std::optional<core::GlassSphere>& glass) {
    return editVolume(s, [&](core::Volume& v) {
        if (glass) {
            core::addGlassSphere(v, *glass);
        } else {
            if (!v.refractiveIndex()) throw ApiError(ErrorCode::InvalidArgument, "the volume has no refractive_index grid to remove");
            v.refractiveIndex().reset();
        }
    });
}

void VolumeService::uploadVdb(Session& s, const std::string& bytes) {
    core::Volume v = readUploadedVdb(bytes);
    std::shared_ptr<core::GpuVolume> stale;
    {
        std::lock_guard lock(s.mutex);
        m_ctx.memory.check(s, v.memoryBytes(), 0, "the uploaded volume");
        s.scene = "upload";  // the session no longer shows its first scene (saved with the version)
        stale = m_ctx.commitVersion(s, std::move(v));
    }
    m_ctx.release(std::move(stale));
}

core::Volume VolumeService::readUploadedVdb(const std::string& bytes) const {
    return readUpload<core::Volume>(bytes, [this](const std::string& path) { return loadUntrustedVdb(path, m_ctx.limits.volumeLimits, m_ctx.limits.vdbReader); });
}

std::map<int, core::Volume> VolumeService::readUploadedVdbFrames(const std::string& bytes) const {
    return readUpload<std::map<int, core::Volume>>(
        bytes, [this](const std::string& path) { return loadUntrustedVdbFrames(path, m_ctx.limits.volumeLimits, m_ctx.limits.vdbReader); });
}

template <typename T>
T VolumeService::readUpload(const std::string& bytes, const std::function<T(const std::string&)>& read) const {
    m_ctx.checkUploadSize(bytes, "the VDB");
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

VdbDownload VolumeService::downloadVdb(Session& s, std::optional<int> version) {
    int n = 0;
    std::optional<std::uintmax_t> stored;
    {
        std::lock_guard lock(s.mutex);
        n = version.value_or(s.volume.version);
        checkVersion(s, n);
        if (m_ctx.persist) stored = s.volume.versions.storedBytes(n);
    }
    const std::string tag = s.id + "-v" + std::to_string(n);
    if (stored) {  // the file as written: no decode, no encode
        try {
            return {m_ctx.persist->readVersionFile(s.id, n, *stored), tag};
        } catch (const Error& e) {
            recordDamage(s, n, e.what());
            checkVersion(s, n);
            throw;
        }
    }
    return {vdbBytes(olderVersion(s, n)), tag};
}

std::string VolumeService::vdbBytes(const core::Volume& v) {
    TempVdb tmp;
    core::saveVdb(tmp.path.string(), v);
    std::ifstream f(tmp.path, std::ios::binary);
    std::stringstream bytes;
    bytes << f.rdbuf();
    return bytes.str();
}

}  // namespace volstyle::server

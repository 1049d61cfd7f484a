#pragma once
/// \file data_dir.h
/// The one way a file reaches the server's data directory (issue #36, "Durability"): written to a
/// temporary file beside its place, fsynced, renamed into place, and the folder fsynced. Without
/// that last step the rename itself may not survive a power loss, so "on disk before the answer"
/// did not hold; and each step's failure is an IoError naming the step and the file (a failed
/// fsync was ignored before). DataDir adds the folder's layout and its quarantine.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace volstyle::server::store {

/// Writes `bytes` to `path` atomically and durably (temporary, fsync, rename, fsync of the folder).
void atomicWrite(const std::filesystem::path& path, const std::string& bytes);

/// The same for a file a library writes itself: `write(tmp)` writes the temporary file (its name
/// keeps `path`'s extension, which image and VDB writers read), then fsync, rename, folder fsync.
void atomicWriteWith(const std::filesystem::path& path, const std::function<void(const std::filesystem::path& tmp)>& write);

/// Renames `from` to `to` (IoError on failure) and fsyncs both folders: a move that must survive.
void durableRename(const std::filesystem::path& from, const std::filesystem::path& to);

/// Flushes a folder's entries (after a rename or a file created in it).
void syncFolder(const std::filesystem::path& dir);

/// Whether `p` is a temporary file a write left behind when the server stopped (restores skip it).
bool isUnfinishedWrite(const std::filesystem::path& p);

/// A file's bytes ("" when it cannot be read: the caller's checks of size and content fail then).
std::string readFile(const std::filesystem::path& p);

/// What the quarantine holds: a file of a session, or a whole session (`file` empty).
struct QuarantineEntry {
    std::string session;
    std::string file;
    std::string reason;
    std::string time;  ///< ISO 8601, UTC
};

/// The data directory: DIR/sessions/<sid>/…, DIR/jobs/<jid>.json and DIR/quarantine/ (issue #9:
/// a file found unreadable is moved there beside a `<file>.reason.json`).
class DataDir {
public:
    explicit DataDir(std::filesystem::path root);  ///< creates sessions/ and jobs/ (IoError if it cannot)

    const std::filesystem::path& root() const { return m_root; }
    std::filesystem::path sessionDir(const std::string& session) const { return m_root / "sessions" / session; }
    std::filesystem::path jobsDir() const { return m_root / "jobs"; }

    /// Moves a session's file (relative to its folder) to the quarantine with its reason.
    void quarantineFile(const std::string& session, const std::string& file, const std::string& reason);
    /// Moves a whole session folder to the quarantine (DIR/quarantine/<sid>/session/).
    void quarantineSession(const std::filesystem::path& dir, const std::string& reason);
    /// Moves a job record that does not read to DIR/quarantine/jobs/.
    void quarantineJobRecord(const std::filesystem::path& record, const std::string& reason);
    /// Everything the quarantine holds, oldest first.
    std::vector<QuarantineEntry> quarantine() const;

private:
    /// `<to>.reason.json` beside a quarantined file or folder.
    void writeReason(const std::filesystem::path& to, const std::string& session, const std::string& file, const std::string& reason);
    std::filesystem::path m_root;
};

}  // namespace volstyle::server::store

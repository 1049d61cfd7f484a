#pragma once
/// \file data_dir.h
/// The one way a file reaches the server's data directory (issue #36, "Durability"): written to a
/// temporary file beside its place, fsynced, renamed into place, and the folder fsynced. Without
/// that last step the rename itself may not survive a power loss, so "on disk before the answer"
/// did not hold; and each step's failure is an IoError naming the step and the file (a failed
/// fsync was ignored before). The start of server/store/.

#include <filesystem>
#include <functional>
#include <string>

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

}  // namespace volstyle::server::store

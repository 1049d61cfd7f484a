#pragma once
/// \file file_mirror.h
/// A second home for the data folder's files (issue #41 item 1): with `serve --store
/// postgresql://…` every file Persistence writes (session records, volume versions, views'
/// images, uploads, frames, the stylizer's scene, job records) is committed to PostgreSQL before
/// the request that wrote it is answered, and the folder becomes a cache that a replica fills from
/// the database when it starts. Paths are relative to the data folder ("sessions/<sid>/1.vdb").

#include <filesystem>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace volstyle::server {

/// A session's file written under its record's stamp check: the write happens only if the record
/// `record` still has stamp `expected` (the copy writing it is the newest), else ApiError busy
/// (409) and nothing is written.
struct RecordGuard {
    std::string record;
    uint64_t expected = 0;
};

class FileMirror {
public:
    virtual ~FileMirror() = default;
    /// Stores the file at `local` as `path` (replacing it), committed when this returns; its
    /// stamp (new at every put: whether a copy read earlier is still the newest).
    virtual uint64_t put(const std::string& path, const std::filesystem::path& local, const RecordGuard* guard = nullptr) = 0;
    /// A session's record and the files it names (its new versions), in one transaction that
    /// first locks the record's row and checks that its stamp is still `expected` (0: no record
    /// yet): two replicas saving one session are serialized, and the one whose copy was stale
    /// gets ApiError busy (409) with nothing written. The record's new stamp.
    virtual uint64_t putRecord(const std::string& record, const std::filesystem::path& recordLocal,
                               const std::vector<std::pair<std::string, std::filesystem::path>>& files, uint64_t expected) = 0;
    /// The stamp of `path` now (nullopt: not stored).
    virtual std::optional<uint64_t> stamp(const std::string& path) = 0;
    virtual void remove(const std::string& path, const RecordGuard* guard = nullptr) = 0;
    /// Removes `prefix` and everything under it ("sessions/<sid>").
    virtual void removeTree(const std::string& prefix, const RecordGuard* guard = nullptr) = 0;
    /// Writes the stored files under `prefix` ("sessions/<sid>", "jobs") into `root` (each at its
    /// path relative to it); the number written. With `recordStamp`, also the stamp of `record`
    /// as of the same moment as the files (nullopt: none).
    virtual size_t materializeTree(const std::string& prefix, const std::filesystem::path& root, const std::string& record = "",
                                   std::optional<uint64_t>* recordStamp = nullptr) = 0;
    /// The stored files `prefix`/<folder>/`name` for each (name, with content) of `names`
    /// ("sessions", {{"summary.json", true}, {"session.json", false}}), as (path, content; "" without),
    /// all read in one snapshot. For small files.
    virtual std::vector<std::pair<std::string, std::string>> readEach(const std::string& prefix,
                                                                      const std::vector<std::pair<std::string, bool>>& names) = 0;
    /// "" when the store takes a write now, else why not (GET /ready).
    virtual std::string writeProblem() = 0;
    /// Where it is, for logs and /ready ("postgresql://host:port/db", no password).
    virtual std::string describe() const = 0;
};

/// The PostgreSQL mirror (pg_file_mirror.cpp): connects to `url` (a libpq connection string or
/// postgresql:// URI) and applies the schema's migrations (refusing a database whose schema is
/// newer than this binary's). Throws IoError when it cannot.
std::unique_ptr<FileMirror> openPostgresMirror(const std::string& url);

/// A store URL as logs and /ready show it: a password (user:secret@) left out.
std::string withoutPassword(const std::string& url);

/// The schema version this binary writes and reads.
constexpr int kStoreSchemaVersion = 2;

}  // namespace volstyle::server

#pragma once
/// \file session_record.h
/// DIR/sessions/<sid>/session.json: a session's own record on disk (format 1), written by the
/// store's encoder, not the API's — id, created, scene, the versions (numbers, the current one,
/// each file's size as written, what is damaged), the lighting, the views (camera, frame, which
/// images it has), the next view number, the jobs and the animation's frames. The files beside it
/// — versions/<N>.vdb, views/<vid>/{target,weights,background}.exr, frames/<n>.vdb and
/// environment.image — are read back here too; a damaged one is quarantined and only what it held
/// is lost (persistence.h).

#include <filesystem>
#include <string>

#include "server/state/session_store.h"
#include "server/store/data_dir.h"

namespace volstyle::server::store {

/// versions/<N>.vdb, relative to the session's folder.
std::string versionFile(int version);

/// The record of `s` (call with its lock held).
std::string encodeSessionRecord(const Session& s);
/// What GET /sessions lists for `s` (the session as GET /sessions/{sid} answers), written beside
/// its record in the store so that any replica lists it without loading it. The caller holds its lock.
std::string encodeSessionSummary(const Session& s);

/// A session restored from its folder: session.json and the files beside it, damage quarantined
/// and listed in its `damaged`. Throws when nothing of it is usable (no record, no readable
/// version): the caller quarantines it whole. The stylizer is restored apart (stylizer_record.h).
/// `recordedDamage`: how much damage the record listed already (more now: write it back).
std::shared_ptr<Session> restoreSessionRecord(DataDir& dir, const std::filesystem::path& folder, size_t& recordedDamage);

/// A stored version read back, its size checked against the one it was written with (0: not
/// checked); IoError if it is missing or damaged.
core::Volume loadVersionFile(const DataDir& dir, const std::string& session, int version, std::uintmax_t expectedBytes);

}  // namespace volstyle::server::store

#pragma once
/// \file vdb_reader.h
/// Uploaded VDBs are read first in a child process (issue #9). Fuzzing found that OpenVDB 10.0
/// (Debian 12) itself overflows a heap buffer, or asks for terabytes, on some damaged files; in
/// the server that aborted the process, so one `PUT …/volume` killed it. The child —
/// `volstyle read-vdb FILE` — loads the file under the volume limits and an address-space limit;
/// only if it succeeds does the server load the file itself (the same code on the same bytes).
/// A child that crashes, runs out of memory or time is a refused upload, not a dead server.

#include <map>
#include <string>
#include <vector>

#include "core/volume/volume.h"

namespace volstyle::server {

struct VdbReaderOptions {
    std::string executable;               ///< the volstyle binary; empty: load in this process
    double seconds = 120;                 ///< the child's wall-clock limit
    std::size_t maxAddressSpaceMiB = 4096;  ///< the child's RLIMIT_AS
};

/// Loads an untrusted VDB file. Throws LimitExceeded (over `limits`), InvalidArgument or IoError
/// (damaged, unsupported, or it crashed the reader) with messages naming the file `nameHint`.
core::Volume loadUntrustedVdb(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader);

/// The same for a VDB holding a whole animation (core::loadVdbFrames; InvalidArgument when no grid
/// is stamped with a frame).
std::map<int, core::Volume> loadUntrustedVdbFrames(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader);

/// The child's side is `volstyle read-vdb FILE --max-voxels N --max-active-voxels N --storage S [--max-memory-mib M] [--frames]`
/// (cli/reader_commands.cpp). Exit status 0 (loads), 3 (over the limits), 4 (invalid), 5
/// (unreadable); the reason on stderr.

}  // namespace volstyle::server

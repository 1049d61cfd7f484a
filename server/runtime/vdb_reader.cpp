#include "server/runtime/vdb_reader.h"

#include "core/base/errors.h"
#include "core/volume/vdb_io.h"
#include "server/runtime/child_process.h"

namespace volstyle::server {
namespace {

/// Reads `path` in the child first (with --frames: as an animation); throws what it refused.
void checkInChild(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader, bool frames) {
    if (reader.executable.empty()) return;
    std::vector<std::string> argv{reader.executable, "read-vdb", path, "--max-voxels", std::to_string(limits.maxVoxels),
                                  "--max-active-voxels", std::to_string(limits.maxActiveVoxels), "--storage",
                                  core::volumeStorageName(limits.storage), "--max-memory-mib", std::to_string(reader.maxAddressSpaceMiB)};
    if (frames) argv.push_back("--frames");
    throwChildFailure(runChild(argv, reader.seconds), path, "VDB", "OpenVDB", reader.seconds);
}

}  // namespace

core::Volume loadUntrustedVdb(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader) {
    checkInChild(path, limits, reader, false);
    return core::loadVdb(path, limits);  // the reader succeeded on these bytes: so does this
}

std::map<int, core::Volume> loadUntrustedVdbFrames(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader) {
    checkInChild(path, limits, reader, true);
    return core::loadVdbFrames(path, limits);
}

}  // namespace volstyle::server

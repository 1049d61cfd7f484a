#include "server/vdb_reader.h"

#include <iostream>

#include "core/base/errors.h"
#include "core/volume/vdb_io.h"
#include "server/child_process.h"
#include "server/cli.h"

namespace volstyle::server {
namespace {

/// Reads `path` in the child first (with --frames: as an animation); throws what it refused.
void checkInChild(const std::string& path, const core::VolumeLimits& limits, const VdbReaderOptions& reader, bool frames) {
    if (reader.executable.empty()) return;
    std::vector<std::string> argv{reader.executable, "read-vdb", path, "--max-voxels", std::to_string(limits.maxVoxels),
                                  "--max-memory-mib", std::to_string(reader.maxAddressSpaceMiB)};
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

int runReadVdb(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, {"max-voxels", "max-memory-mib"}, {"frames"});
    if (args.positional.size() != 1) throw InvalidArgument("usage: volstyle read-vdb FILE --max-voxels N [--max-memory-mib M]");
    core::VolumeLimits limits;
    limits.maxVoxels = int64_t(args.number("max-voxels", double(limits.maxVoxels)));
    const double mib = args.number("max-memory-mib", 4096);
    limitChildMemory(mib);
    const std::string path = args.positional[0];
    return childExitStatus(
        [&] {
            if (args.has("frames")) {
                if (core::loadVdbFrames(path, limits).empty())
                    throw InvalidArgument("the file holds no grids stamped with a frame (density.12, vel_12, or a 'frame' metadata entry)");
            } else {
                core::loadVdb(path, limits);
            }
        },
        path, mib);
}

}  // namespace volstyle::server

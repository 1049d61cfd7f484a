// The server's child readers: `volstyle read-vdb` and `volstyle read-mesh` parse an untrusted
// upload in their own process under an address-space limit (server/runtime/vdb_reader.h,
// mesh_reader.h run them), so a reader that crashes or runs away takes only the child down.

#include <fstream>
#include <iterator>

#include "cli/cli.h"
#include "core/base/errors.h"
#include "core/stylize/mesh_io.h"
#include "core/volume/vdb_io.h"
#include "protocol/mesh_upload_check.h"
#include "server/runtime/child_process.h"
#include "server/runtime/mesh_transfer.h"

namespace volstyle::cli {

int runReadVdb(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, {"max-voxels", "max-active-voxels", "storage", "max-memory-mib"}, {"frames"});
    if (args.positional.size() != 1)
        throw InvalidArgument("usage: volstyle read-vdb FILE --max-voxels N [--max-active-voxels N] [--storage auto|dense|sparse] [--max-memory-mib M]");
    core::VolumeLimits limits;
    limits.maxVoxels = int64_t(args.number("max-voxels", double(limits.maxVoxels)));
    limits.maxActiveVoxels = int64_t(args.number("max-active-voxels", double(limits.maxActiveVoxels)));
    limits.storage = core::volumeStorageNamed(args.get("storage", "auto"));
    const double mib = args.number("max-memory-mib", 4096);
    server::limitChildMemory(mib);
    const std::string path = args.positional[0];
    return server::childExitStatus(
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

int runReadMesh(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, {"format", "out", "max-vertices", "max-triangles", "max-memory-mib"}, {});
    if (args.positional.size() != 1 || !args.has("format") || !args.has("out"))
        throw InvalidArgument("usage: volstyle read-mesh FILE --format obj|ply|gltf|glb --out OUT [--max-vertices N] [--max-triangles N]");
    core::MeshLimits limits;
    limits.maxVertices = size_t(args.number("max-vertices", double(limits.maxVertices)));
    limits.maxTriangles = size_t(args.number("max-triangles", double(limits.maxTriangles)));
    const double mib = args.number("max-memory-mib", 4096);
    server::limitChildMemory(mib);
    const std::string path = args.positional[0];
    return server::childExitStatus(
        [&] {
            std::ifstream f(path, std::ios::binary);
            const std::string bytes{std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
            const std::string format = args.get("format");
            protocol::checkMeshUpload(bytes, format, limits);  // the server checked; a child run by hand checks too
            server::writeMeshTransfer(core::loadMeshFromMemory(bytes, format, limits), args.get("out"));
        },
        "the uploaded mesh", mib);
}

}  // namespace volstyle::cli

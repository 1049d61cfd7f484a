#include "server/runtime/mesh_reader.h"

#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/base/errors.h"
#include "core/stylize/mesh_io.h"
#include "protocol/mesh_upload_check.h"
#include "server/runtime/child_process.h"
#include "server/runtime/mesh_transfer.h"

namespace volstyle::server {
namespace {

namespace fs = std::filesystem;

/// A file in the temporary folder, removed with this object.
struct TempFile {
    std::string path;
    explicit TempFile(const std::string& suffix) {
        static std::atomic<uint64_t> counter{0};
        path = (fs::temp_directory_path() / ("volstyle-mesh-" + std::to_string(::getpid()) + "-" + std::to_string(++counter) + suffix)).string();
    }
    ~TempFile() {
        std::error_code ec;
        fs::remove(path, ec);
    }
};

}  // namespace

core::Mesh loadUntrustedMesh(const std::string& bytes, const std::string& format, const core::MeshLimits& limits,
                             const VdbReaderOptions& reader) {
    if (bytes.size() > limits.maxFileBytes)
        throw LimitExceeded("the uploaded mesh is " + std::to_string(bytes.size()) + " bytes, over the limit of " +
                            std::to_string(limits.maxFileBytes));
    try {
        protocol::checkMeshUpload(bytes, format, limits);
    } catch (const Error& e) {
        if (dynamic_cast<const LimitExceeded*>(&e)) throw LimitExceeded("the uploaded mesh: " + std::string(e.what()));
        throw InvalidArgument("the uploaded mesh: " + std::string(e.what()));
    }
    if (reader.executable.empty()) return core::loadMeshFromMemory(bytes, format, limits);
    TempFile in("." + format), out(".mesh");
    {
        std::ofstream f(in.path, std::ios::binary | std::ios::trunc);
        f.write(bytes.data(), std::streamsize(bytes.size()));
        if (!f) throw IoError("cannot write the uploaded mesh to " + in.path);
    }
    const std::vector<std::string> argv{reader.executable, "read-mesh", in.path, "--format", format, "--out", out.path,
                                        "--max-vertices", std::to_string(limits.maxVertices), "--max-triangles",
                                        std::to_string(limits.maxTriangles), "--max-memory-mib", std::to_string(reader.maxAddressSpaceMiB)};
    throwChildFailure(runChild(argv, reader.seconds), "the uploaded mesh", "mesh", "assimp", reader.seconds);
    return readMeshTransfer(out.path, limits);
}

}  // namespace volstyle::server

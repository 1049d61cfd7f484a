#include "server/mesh_reader.h"

#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/base/errors.h"
#include "core/stylize/mesh_io.h"
#include "protocol/mesh_upload_check.h"
#include "server/child_process.h"
#include "server/cli.h"

namespace volstyle::server {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'V', 'S', 'M', 'E', 'S', 'H', '1', '\0'};

/// The child's answer: magic, vertex count, index count (uint64 each), then positions and
/// normals (3 floats a vertex each) and the indices (uint32).
void writeMesh(const core::Mesh& m, const std::string& path) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    const uint64_t counts[2] = {m.positions.size(), m.indices.size()};
    out.write(kMagic, sizeof kMagic);
    out.write(reinterpret_cast<const char*>(counts), sizeof counts);
    out.write(reinterpret_cast<const char*>(m.positions.data()), std::streamsize(m.positions.size() * sizeof(Vec3)));
    out.write(reinterpret_cast<const char*>(m.normals.data()), std::streamsize(m.normals.size() * sizeof(Vec3)));
    out.write(reinterpret_cast<const char*>(m.indices.data()), std::streamsize(m.indices.size() * sizeof(uint32_t)));
    if (!out) throw IoError("cannot write the mesh to " + path);
}

core::Mesh readMesh(const std::string& path, const core::MeshLimits& limits) {
    std::ifstream in(path, std::ios::binary);
    char magic[8];
    uint64_t counts[2];
    if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0 ||
        !in.read(reinterpret_cast<char*>(counts), sizeof counts))
        throw IoError("the mesh reader's answer is damaged");
    if (counts[0] > limits.maxVertices || counts[1] > 3 * uint64_t(limits.maxTriangles) || counts[1] % 3 != 0)
        throw IoError("the mesh reader's answer is over the limits it was given");
    const uint64_t expected = sizeof magic + sizeof counts + counts[0] * 2 * sizeof(Vec3) + counts[1] * sizeof(uint32_t);
    if (fs::file_size(path) != expected) throw IoError("the mesh reader's answer is damaged (its size does not match its counts)");
    core::Mesh m;
    m.positions.resize(counts[0]);
    m.normals.resize(counts[0]);
    m.indices.resize(counts[1]);
    in.read(reinterpret_cast<char*>(m.positions.data()), std::streamsize(counts[0] * sizeof(Vec3)));
    in.read(reinterpret_cast<char*>(m.normals.data()), std::streamsize(counts[0] * sizeof(Vec3)));
    in.read(reinterpret_cast<char*>(m.indices.data()), std::streamsize(counts[1] * sizeof(uint32_t)));
    if (!in) throw IoError("the mesh reader's answer is truncated");
    m.validate();
    return m;
}

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
    return readMesh(out.path, limits);
}

int runReadMesh(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, {"format", "out", "max-vertices", "max-triangles", "max-memory-mib"}, {});
    if (args.positional.size() != 1 || !args.has("format") || !args.has("out"))
        throw InvalidArgument("usage: volstyle read-mesh FILE --format obj|ply|gltf|glb --out OUT [--max-vertices N] [--max-triangles N]");
    core::MeshLimits limits;
    limits.maxVertices = size_t(args.number("max-vertices", double(limits.maxVertices)));
    limits.maxTriangles = size_t(args.number("max-triangles", double(limits.maxTriangles)));
    const double mib = args.number("max-memory-mib", 4096);
    limitChildMemory(mib);
    const std::string path = args.positional[0];
    return childExitStatus(
        [&] {
            std::ifstream f(path, std::ios::binary);
            const std::string bytes{std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
            const std::string format = args.get("format");
            protocol::checkMeshUpload(bytes, format, limits);  // the server checked; a child run by hand checks too
            writeMesh(core::loadMeshFromMemory(bytes, format, limits), args.get("out"));
        },
        "the uploaded mesh", mib);
}

}  // namespace volstyle::server

#include "server/runtime/mesh_transfer.h"

#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/base/errors.h"

namespace volstyle::server {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'V', 'S', 'M', 'E', 'S', 'H', '1', '\0'};

}  // namespace

/// The child's answer: magic, vertex count, index count (uint64 each), then positions and
/// normals (3 floats a vertex each) and the indices (uint32).
void writeMeshTransfer(const core::Mesh& m, const std::string& path) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    const uint64_t counts[2] = {m.positions.size(), m.indices.size()};
    out.write(kMagic, sizeof kMagic);
    out.write(reinterpret_cast<const char*>(counts), sizeof counts);
    out.write(reinterpret_cast<const char*>(m.positions.data()), std::streamsize(m.positions.size() * sizeof(Vec3)));
    out.write(reinterpret_cast<const char*>(m.normals.data()), std::streamsize(m.normals.size() * sizeof(Vec3)));
    out.write(reinterpret_cast<const char*>(m.indices.data()), std::streamsize(m.indices.size() * sizeof(uint32_t)));
    if (!out) throw IoError("cannot write the mesh to " + path);
}

core::Mesh readMeshTransfer(const std::string& path, const core::MeshLimits& limits) {
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

}  // namespace volstyle::server

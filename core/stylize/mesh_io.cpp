// The only translation unit that includes assimp.
#include "core/stylize/mesh_io.h"

#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <vector>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

namespace fs = std::filesystem;

// No aiProcess_PreTransformVertices: it expands every instance of a mesh before anything can be
// counted (a 32 KB glTF whose nodes reuse each other took 8.6 GB). The node tree is walked here
// instead: instances are counted first against the limits, then expanded.
constexpr unsigned kSteps = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_GenSmoothNormals |
                            aiProcess_SortByPType | aiProcess_ValidateDataStructure;

/// An IO system without files (uploads): opening anything fails.
class NoFiles : public Assimp::IOSystem {
public:
    bool Exists(const char*) const override { return false; }
    char getOsSeparator() const override { return '/'; }
    Assimp::IOStream* Open(const char*, const char*) override { return nullptr; }
    void Close(Assimp::IOStream* stream) override { delete stream; }
};

void configure(Assimp::Importer& importer) {
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
}

/// Vertices and triangles of every mesh instance below `node`, stopping once over the limits.
void countInstances(const aiScene* scene, const aiNode* node, const MeshLimits& limits, size_t& vertices,
                    size_t& triangles, int depth) {
    if (depth > 64 || vertices > limits.maxVertices || triangles > limits.maxTriangles) return;
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
        const aiMesh* m = scene->mMeshes[node->mMeshes[i]];
        if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        vertices += m->mNumVertices;
        triangles += m->mNumFaces;
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) countInstances(scene, node->mChildren[c], limits, vertices, triangles, depth + 1);
}

void appendInstances(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent, Mesh& out, int depth) {
    if (depth > 64) return;
    const aiMatrix4x4 xf = parent * node->mTransformation;
    aiMatrix3x3 normalXf(xf);
    normalXf.Inverse().Transpose();
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
        const aiMesh* mesh = scene->mMeshes[node->mMeshes[i]];
        if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        const auto offset = uint32_t(out.positions.size());
        for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
            const aiVector3D p = xf * mesh->mVertices[v];
            out.positions.emplace_back(p.x, p.y, p.z);
            Vec3 n(0, 1, 0);
            if (mesh->mNormals) {
                const aiVector3D q = normalXf * mesh->mNormals[v];
                n = Vec3(q.x, q.y, q.z);
            }
            const float len = length(n);
            out.normals.push_back(std::isfinite(len) && len > 0 ? n / len : Vec3(0, 1, 0));  // degenerate: any unit
        }
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;  // points and lines are removed; be safe
            for (int k = 0; k < 3; ++k) out.indices.push_back(offset + face.mIndices[k]);
        }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) appendInstances(scene, node->mChildren[c], xf, out, depth + 1);
}

Mesh flatten(const aiScene* scene, const std::string& what, const MeshLimits& limits) {
    size_t vertices = 0, triangles = 0;
    countInstances(scene, scene->mRootNode, limits, vertices, triangles, 0);
    if (vertices > limits.maxVertices)
        throw LimitExceeded(what + " has over " + std::to_string(limits.maxVertices) + " vertices (instances counted), the limit");
    if (triangles > limits.maxTriangles)
        throw LimitExceeded(what + " has over " + std::to_string(limits.maxTriangles) + " triangles (instances counted), the limit");
    Mesh out;
    out.positions.reserve(vertices);
    out.normals.reserve(vertices);
    out.indices.reserve(3 * triangles);
    appendInstances(scene, scene->mRootNode, aiMatrix4x4(), out, 0);
    if (out.indices.empty()) throw InvalidArgument(what + " holds no triangles");
    for (size_t i = 0; i < out.positions.size(); ++i) {
        const Vec3& p = out.positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || std::abs(p.x) > 1e18f ||
            std::abs(p.y) > 1e18f || std::abs(p.z) > 1e18f)
            throw InvalidArgument(what + ": vertex " + std::to_string(i) + " has a non-finite or out-of-range position (|x| > 1e18)");
    }
    out.validate();
    return out;
}

/// The formats volstyle documents (assimp reads many more; each is more code a hostile file reaches).
void requireKnownFormat(const std::string& extension, const std::string& what) {
    static const char* const kKnown[] = {"obj", "ply", "gltf", "glb"};
    if (std::find(std::begin(kKnown), std::end(kKnown), extension) == std::end(kKnown))
        throw InvalidArgument(what + ": mesh format '" + extension + "' is not one of obj, ply, gltf, glb");
}

/// Bytes of one PLY scalar type (0: not a type PLY defines).
double plyTypeBytes(const std::string& t) {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    return 0;
}

/// A PLY header line's words, split on spaces and tabs only.
std::vector<std::string> plyWords(const std::string& line) {
    std::vector<std::string> words;
    for (size_t at = 0; at < line.size();) {
        const size_t start = line.find_first_not_of(" \t", at);
        if (start == std::string::npos) break;
        const size_t end = std::min(line.find_first_of(" \t", start), line.size());
        words.push_back(line.substr(start, end - start));
        at = end;
    }
    return words;
}

/// A PLY header, checked line by line against the grammar and its element counts against the
/// bytes present: assimp allocates what the header claims before reading (a 200-byte file
/// claiming 10⁸ vertices took 1.3 GB), and loops forever on headers it half-understands
/// (fuzz_mesh_ply: an `end_header` behind a vertical tab). Lines end with LF, CRLF or CR alone (a
/// CR-only header once hid its counts from this check); a line is `ply`, `format`, `comment`,
/// `obj_info`, `element NAME COUNT`, `property TYPE NAME`, `property list TYPE TYPE NAME` or
/// `end_header`, nothing else; counts are read as decimal text, so 2⁶⁴ + 10⁹ is a huge count, not
/// a wrapped or an unread one. Each element needs at least its properties' bytes (binary) or two
/// characters a value (ASCII); a face list at least three indices.
void checkPlyHeader(const std::string& bytes, const std::string& what, const MeshLimits& limits) {
    const size_t headEnd = std::min<size_t>(bytes.size(), 64 * 1024);
    bool binary = false, ended = false, formatSeen = false;
    size_t at = 0, bodyStart = bytes.size();
    struct Element {
        std::string name;
        double count = 0, minBytes = 0;
    };
    std::vector<Element> elements;
    const auto refuse = [&](int number, const std::string& line, const std::string& why) {
        std::string shown;
        for (char c : line.substr(0, 60)) shown += (c >= 0x20 && c < 0x7f) ? c : '?';
        throw InvalidArgument(what + ": PLY header line " + std::to_string(number) + " ('" + shown + "') " + why);
    };
    std::string newline;  // the first line's ending; every header line must end alike
    for (int number = 1; at < headEnd && !ended; ++number) {
        size_t end = bytes.find_first_of("\r\n", at);
        if (end == std::string::npos || end > headEnd) end = headEnd;
        const std::string line = bytes.substr(at, end - at);
        const std::string ending = bytes.compare(end, 2, "\r\n") == 0 ? "\r\n" : bytes.substr(std::min(end, bytes.size()), 1);
        if (newline.empty()) newline = ending;
        else if (ending != newline) refuse(number, line, "ends its line unlike the first line (mixed line endings loop assimp)");
        at = end + ending.size();
        for (char c : line)
            if (static_cast<unsigned char>(c) < 0x20 && c != '\t') refuse(number, line, "holds a control character");
        const std::vector<std::string> w = plyWords(line);
        const std::string keyword = w.empty() ? "" : w[0];
        if (number == 1) {
            if (line != "ply") refuse(number, line, "is not 'ply'");
        } else if (keyword == "comment" || keyword == "obj_info") {
        } else if (keyword == "format") {
            if (formatSeen || w.size() != 3 || w[2] != "1.0" ||
                (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
                refuse(number, line, formatSeen ? "is a second format line" : "is not 'format ascii|binary_little_endian|binary_big_endian 1.0'");
            binary = w[1] != "ascii";
            formatSeen = true;
        } else if (keyword == "element") {
            if (w.size() != 3 || w[2].find_first_not_of("0123456789") != std::string::npos)
                refuse(number, line, "is not 'element NAME COUNT'");
            elements.push_back({w[1], w[2].size() > 18 ? 1e300 : double(std::stoull(w[2])), 0});
        } else if (keyword == "property" && !elements.empty()) {
            double b = 0;
            if (w.size() == 5 && w[1] == "list" && plyTypeBytes(w[2]) > 0 && plyTypeBytes(w[3]) > 0)
                b = binary ? plyTypeBytes(w[2]) + 3 * plyTypeBytes(w[3]) : 8;  // "3 0 1 2"
            else if (w.size() == 3 && plyTypeBytes(w[1]) > 0)
                b = binary ? plyTypeBytes(w[1]) : 2;  // "0 "
            else
                refuse(number, line, "is not 'property TYPE NAME' or 'property list TYPE TYPE NAME' with PLY's types");
            elements.back().minBytes += b;
        } else if (line.substr(0, line.find_last_not_of(" \t") + 1) == "end_header") {
            ended = true;
            bodyStart = std::min(at, bytes.size());
        } else {
            refuse(number, line, "is not a line PLY's header may hold");
        }
    }
    if (!ended) throw InvalidArgument(what + ": the PLY header has no end_header line within its first 64 KiB");
    if (!formatSeen) throw InvalidArgument(what + ": the PLY header has no format line");
    double vertices = 0, faces = 0, need = 0;
    for (const auto& e : elements) {
        if (e.name == "vertex") vertices = e.count;
        if (e.name == "face") faces = e.count;
        need += e.count * std::max(e.minBytes, 1.0);
    }
    const auto text = [](double x) { return x >= 1e18 ? std::string("over 10^18") : std::to_string(uint64_t(x)); };
    if (vertices > double(limits.maxVertices) || faces > double(limits.maxTriangles))
        throw LimitExceeded(what + " declares " + text(vertices) + " vertices and " + text(faces) + " faces, over the limits (" +
                            std::to_string(limits.maxVertices) + " vertices, " + std::to_string(limits.maxTriangles) + " faces)");
    const double body = double(bytes.size() - bodyStart);
    if (need > body)
        throw InvalidArgument(what + " is truncated: its header declares " + text(vertices) + " vertices and " + text(faces) +
                              " faces, which need at least " + text(need) + " bytes; " + text(body) + " follow the header");
}

std::string lowerExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

}  // namespace

Mesh loadMesh(const std::string& path, const MeshLimits& limits) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw IoError("no such file " + quoted(path));
    if (fs::is_directory(path, ec)) throw IoError(quoted(path) + " is a folder, not a mesh file");
    const auto bytes = fs::file_size(path, ec);
    if (ec) throw IoError("cannot read " + quoted(path) + ": " + ec.message());
    if (bytes == 0) throw IoError(quoted(path) + " is empty");
    if (bytes > limits.maxFileBytes)
        throw LimitExceeded(quoted(path) + " is " + std::to_string(bytes) + " bytes, over the limit of " +
                            std::to_string(limits.maxFileBytes));
    requireKnownFormat(lowerExtension(path), quoted(path));
    if (lowerExtension(path) == "ply") {
        std::ifstream in(path, std::ios::binary);
        const std::string all{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
        checkPlyHeader(all, quoted(path), limits);
    }
    Assimp::Importer importer;
    configure(importer);
    const aiScene* scene = importer.ReadFile(path, kSteps);
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->HasMeshes())
        throw IoError(quoted(path) + " could not be read as a mesh (OBJ, PLY, glTF): " +
                      std::string(scene && !scene->HasMeshes() ? "it holds no meshes" : importer.GetErrorString()));
    return flatten(scene, quoted(path), limits);
}

std::string meshFormatOf(const std::string& bytes) {
    if (bytes.rfind("glTF", 0) == 0) return "glb";
    if (bytes.rfind("ply", 0) == 0 && bytes.size() > 3 && (bytes[3] == '\n' || bytes[3] == '\r')) return "ply";
    const size_t first = bytes.find_first_not_of(" \t\r\n");
    if (first != std::string::npos && bytes[first] == '{') return "gltf";
    return "obj";
}

Mesh loadMeshFromMemory(const std::string& bytes, const std::string& extension, const MeshLimits& limits) {
    const std::string what = "the uploaded mesh";
    if (bytes.empty()) throw InvalidArgument(what + " is empty");
    if (bytes.size() > limits.maxFileBytes)
        throw LimitExceeded(what + " is " + std::to_string(bytes.size()) + " bytes, over the limit of " +
                            std::to_string(limits.maxFileBytes));
    requireKnownFormat(extension, what);
    if (extension == "ply") checkPlyHeader(bytes, what, limits);
    Assimp::Importer importer;
    configure(importer);
    // ReadFileFromMemory serves the bytes and hands every other name (a glTF buffer's or image's
    // URI) to the importer's IO system: with the default one a glTF upload could read any file
    // of the server's. This one has none, so only data: URIs (embedded) resolve.
    importer.SetIOHandler(new NoFiles);
    const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kSteps, extension.c_str());
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->HasMeshes()) {
        // In assimp's words, without its internals: the name it gives the bytes, and its check
        // that a scene has meshes (what a file that is no mesh at all fails).
        std::string reason = scene && !scene->HasMeshes() ? "it holds no meshes" : importer.GetErrorString();
        if (reason.find("mNumMeshes is 0") != std::string::npos) reason = "it holds no meshes (is it a mesh file?)";
        const std::string magic = "\"$$$___magic___$$$." + extension + "\"";
        for (size_t at; (at = reason.find(magic)) != std::string::npos;) reason.replace(at, magic.size(), "the upload");
        if (reason.find("No suitable reader") != std::string::npos) reason = "it is not a readable " + extension + " file (truncated or damaged?)";
        throw InvalidArgument(what + " could not be read as " + extension + ": " + reason);
    }
    return flatten(scene, what, limits);
}

}  // namespace volstyle::core

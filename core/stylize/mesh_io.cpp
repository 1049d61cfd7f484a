// The only translation unit that includes assimp.
#include "core/stylize/mesh_io.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

namespace fs = std::filesystem;

constexpr unsigned kSteps = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                            aiProcess_GenSmoothNormals | aiProcess_SortByPType | aiProcess_ValidateDataStructure;

void configure(Assimp::Importer& importer) {
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
}

Mesh flatten(const aiScene* scene, const std::string& what, const MeshLimits& limits) {
    Mesh out;
    size_t vertices = 0, triangles = 0;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        vertices += scene->mMeshes[m]->mNumVertices;
        triangles += scene->mMeshes[m]->mNumFaces;
    }
    if (vertices > limits.maxVertices)
        throw LimitExceeded(what + " has " + std::to_string(vertices) + " vertices, over the limit of " +
                            std::to_string(limits.maxVertices));
    if (triangles > limits.maxTriangles)
        throw LimitExceeded(what + " has " + std::to_string(triangles) + " triangles, over the limit of " +
                            std::to_string(limits.maxTriangles));
    out.positions.reserve(vertices);
    out.normals.reserve(vertices);
    out.indices.reserve(3 * triangles);
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh* mesh = scene->mMeshes[m];
        if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        const auto offset = uint32_t(out.positions.size());
        for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
            const aiVector3D& p = mesh->mVertices[v];
            out.positions.emplace_back(p.x, p.y, p.z);
            Vec3 n(0, 1, 0);
            if (mesh->mNormals) n = Vec3(mesh->mNormals[v].x, mesh->mNormals[v].y, mesh->mNormals[v].z);
            const float len = length(n);
            out.normals.push_back(std::isfinite(len) && len > 0 ? n / len : Vec3(0, 1, 0));  // degenerate: any unit
        }
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;  // points and lines are removed; be safe
            for (int k = 0; k < 3; ++k) out.indices.push_back(offset + face.mIndices[k]);
        }
    }
    if (out.indices.empty()) throw InvalidArgument(what + " holds no triangles");
    for (size_t i = 0; i < out.positions.size(); ++i) {
        const Vec3& p = out.positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw InvalidArgument(what + ": vertex " + std::to_string(i) + " has a non-finite position");
    }
    out.validate();
    return out;
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
    Assimp::Importer importer;
    configure(importer);
    const aiScene* scene = importer.ReadFile(path, kSteps);
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->HasMeshes())
        throw IoError(quoted(path) + " could not be read as a mesh (OBJ, PLY, glTF): " +
                      std::string(scene && !scene->HasMeshes() ? "it holds no meshes" : importer.GetErrorString()));
    return flatten(scene, quoted(path), limits);
}

Mesh loadMeshFromMemory(const std::string& bytes, const std::string& extension, const MeshLimits& limits) {
    const std::string what = "the uploaded mesh";
    if (bytes.empty()) throw InvalidArgument(what + " is empty");
    if (bytes.size() > limits.maxFileBytes)
        throw LimitExceeded(what + " is " + std::to_string(bytes.size()) + " bytes, over the limit of " +
                            std::to_string(limits.maxFileBytes));
    static const char* const kKnown[] = {"obj", "ply", "gltf", "glb"};
    if (std::find(std::begin(kKnown), std::end(kKnown), extension) == std::end(kKnown))
        throw InvalidArgument("mesh format " + quoted(extension) + " is not one of obj, ply, gltf, glb");
    Assimp::Importer importer;
    configure(importer);
    const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kSteps, extension.c_str());
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->HasMeshes())
        throw InvalidArgument(what + " could not be read as " + extension + ": " +
                              std::string(scene && !scene->HasMeshes() ? "it holds no meshes" : importer.GetErrorString()));
    return flatten(scene, what, limits);
}

}  // namespace volstyle::core

#pragma once
/// \file mesh_io.h
/// Occluder meshes from OBJ, PLY and glTF 2.0 (.gltf with embedded or neighbouring buffers, .glb)
/// through assimp (Debian's libassimp, kept inside mesh_io.cpp). Every mesh of the file is
/// flattened into one, with its node transforms applied, triangulated, with smooth normals where
/// the file has none; points and lines are dropped.

#include <string>

#include "core/stylize/mesh.h"

namespace volstyle::core {

/// Reads a mesh file. Throws IoError (missing, unreadable, corrupt, not a mesh format assimp
/// knows), InvalidArgument (no triangles, non-finite vertices) or LimitExceeded (over `limits`).
Mesh loadMesh(const std::string& path, const MeshLimits& limits = {});

/// The format of mesh bytes by their first bytes: "glb" (binary glTF's magic), "ply" (its magic
/// line), "gltf" (a JSON object), else "obj" (text; assimp then judges it).
std::string meshFormatOf(const std::string& bytes);

/// The same from bytes in memory (uploads); `extension` ("obj", "ply", "gltf", "glb") tells the
/// format. A .gltf whose buffers are separate files cannot be read this way (upload a .glb).
Mesh loadMeshFromMemory(const std::string& bytes, const std::string& extension, const MeshLimits& limits = {});

}  // namespace volstyle::core

#pragma once
// libFuzzer harness body for uploaded meshes of one format, as the server's child reader reads
// them (server/runtime/mesh_reader.h): the structure check at the door (protocol/mesh_upload_check.h),
// then assimp through core::loadMeshFromMemory (the PLY header check first). Our code must refuse
// damaged files with a volstyle error; crashes inside assimp are what the child process contains
// (scripts/fuzz.sh reports them apart).
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/base/errors.h"
#include "core/stylize/mesh_io.h"
#include "protocol/mesh_upload_check.h"

inline int fuzzMesh(const uint8_t* data, size_t size, const char* format) {
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    volstyle::core::MeshLimits limits;
    limits.maxVertices = 100'000;
    limits.maxTriangles = 200'000;
    try {
        // "gltf" fuzzes both containers: the bytes decide (as meshFormatOf does for uploads).
        const std::string f = std::string(format) == "gltf" ? volstyle::core::meshFormatOf(bytes) : format;
        if (std::string(format) == "gltf" && f != "glb" && f != "gltf") return 0;
        volstyle::protocol::checkMeshUpload(bytes, f, limits);
        volstyle::core::loadMeshFromMemory(bytes, f, limits);
    } catch (const volstyle::Error&) {
    }
    return 0;
}

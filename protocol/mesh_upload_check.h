#pragma once
/// \file mesh_upload_check.h
/// What an uploaded glTF or GLB says about itself, checked before any mesh library reads it
/// (issue #35). assimp 5.2.5 builds its node tree by recursion (a chain of 20,000 nested nodes
/// overflowed the server's stack) and copies a node once per reference (a 1 KB file whose nodes
/// each reference the next twice, 24 levels, took 10.75 GB). Here the JSON is parsed with
/// nlohmann (iterative) and the node graph is walked once, memoised, without expanding it:
/// nesting, cycles, expanded node count and expanded vertices are known before anything is
/// allocated for them. The GLB container's lengths must add up to the bytes present, buffers must
/// fit what holds them, and required extensions must be ones the reader honours.

#include <string>

#include "core/stylize/mesh.h"

namespace volstyle::protocol {

/// Limits of a glTF's structure (beyond MeshLimits' vertices and triangles).
struct GltfLimits {
    int maxJsonDepth = 64;           ///< nesting of JSON arrays and objects
    int maxNodeDepth = 64;           ///< nesting of the node tree
    size_t maxExpandedNodes = 100'000;  ///< nodes once every reference is expanded into a copy
};

/// Throws InvalidArgument (self-contradictory, unsupported required extension, cyclic, too deep)
/// or LimitExceeded (more expanded nodes, vertices or triangles than allowed) for a "gltf" or
/// "glb" upload; other formats pass (their readers check their own headers).
void checkMeshUpload(const std::string& bytes, const std::string& format, const core::MeshLimits& limits,
                     const GltfLimits& gltf = {});

}  // namespace volstyle::protocol

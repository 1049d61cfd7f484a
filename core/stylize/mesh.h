#pragma once
/// \file mesh.h
/// Triangle meshes for the light-shaft stylizer's occluders (SPEC §7): positions, per-vertex
/// normals and triangle indices, in the mesh's own space (the scene's per-object transform is
/// applied on the GPU). GL-free. Files are read by mesh_io.h.

#include <cstdint>
#include <vector>

#include "core/math/vec.h"

namespace volstyle::core {

struct Mesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;      ///< one per position, unit length
    std::vector<uint32_t> indices;  ///< three per triangle

    size_t triangleCount() const { return indices.size() / 3; }
    /// Axis-aligned bounds of the positions ({0,0,0} twice when empty).
    std::pair<Vec3, Vec3> bounds() const;
    /// Appends `other` (indices offset).
    void append(const Mesh& other);
    /// Throws InvalidArgument naming the problem: no triangles, indices not a multiple of 3 or out
    /// of range, normals not one per position, non-finite positions or normals.
    void validate() const;
};

/// Limits on what a mesh file may hold (uploads, CLI).
struct MeshLimits {
    size_t maxVertices = 4'000'000;
    size_t maxTriangles = 8'000'000;
    size_t maxFileBytes = size_t(256) << 20;
};

}  // namespace volstyle::core

#include "core/stylize/mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/base/errors.h"

namespace volstyle::core {

std::pair<Vec3, Vec3> Mesh::bounds() const {
    if (positions.empty()) return {Vec3(0.0f), Vec3(0.0f)};
    Vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const Vec3& p : positions)
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    return {lo, hi};
}

void Mesh::append(const Mesh& other) {
    const auto offset = uint32_t(positions.size());
    positions.insert(positions.end(), other.positions.begin(), other.positions.end());
    normals.insert(normals.end(), other.normals.begin(), other.normals.end());
    for (uint32_t i : other.indices) indices.push_back(i + offset);
}

void Mesh::validate() const {
    if (indices.empty()) throw InvalidArgument("the mesh has no triangles");
    if (indices.size() % 3 != 0) throw InvalidArgument("the mesh's index count is not a multiple of 3");
    if (normals.size() != positions.size())
        throw InvalidArgument("the mesh has " + std::to_string(normals.size()) + " normals for " +
                              std::to_string(positions.size()) + " vertices");
    for (size_t i = 0; i < indices.size(); ++i)
        if (indices[i] >= positions.size())
            throw InvalidArgument("triangle " + std::to_string(i / 3) + " uses vertex " + std::to_string(indices[i]) +
                                  " of " + std::to_string(positions.size()));
    auto finite = [](const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    for (size_t i = 0; i < positions.size(); ++i) {
        if (!finite(positions[i])) throw InvalidArgument("vertex " + std::to_string(i) + " has a non-finite position");
        if (!finite(normals[i])) throw InvalidArgument("vertex " + std::to_string(i) + " has a non-finite normal");
    }
}

}  // namespace volstyle::core

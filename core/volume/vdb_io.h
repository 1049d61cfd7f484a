#pragma once
/// \file vdb_io.h
/// OpenVDB files (SPEC §1): grids `extinction` (float or Vec3f) or float `density`, `emission`
/// and `albedo` (Vec3f or float), optional float `refractive_index`. OpenVDB headers stay inside
/// vdb_io.cpp.

#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// Reads a VDB into a dense volume over the extinction grid's active bounding box; other grids are
/// resampled onto it when their transform differs. Throws IoError (missing, corrupt, truncated) or
/// InvalidArgument (no extinction grid, unsupported grid type, non-linear transform, values out of
/// range, over `limits`).
Volume loadVdb(const std::string& path, const VolumeLimits& limits = {});

/// Writes sparse grids: only voxels with non-zero extinction are active (albedo and emission are
/// written at those voxels), stored as leaf voxels — never as tiles, which Blender's Cycles (3.4)
/// renders as empty. Grey extinction is written as float `density`, chromatic as Vec3f
/// `extinction`. The transform is kept. Writes to a temporary file and renames it into place.
void saveVdb(const std::string& path, const Volume& volume);

/// Summary of one grid in a file, for `volstyle info`.
struct VdbGridInfo {
    std::string name;
    std::string type;         ///< "float", "vec3s", ...
    std::string gridClass;    ///< "fog volume", "level set", "unknown", ...
    int64_t activeVoxels = 0;
    Int3 activeMin, activeMax;  ///< active bounding box (inclusive), index space
    Vec3d voxelSize;
    Mat4 worldFromIndex;
    bool isLinearTransform = true;
    Vec3 minValue, maxValue;  ///< per channel over active values (float grids repeat)
};

std::vector<VdbGridInfo> inspectVdb(const std::string& path);

}  // namespace volstyle::core

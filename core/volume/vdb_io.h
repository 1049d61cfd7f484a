#pragma once
/// \file vdb_io.h
/// OpenVDB files (SPEC §1): grids `extinction` (float or Vec3f) or float `density`, `emission`
/// and `albedo` (Vec3f or float), optional float `refractive_index`. OpenVDB headers stay inside
/// vdb_read.cpp and vdb_write.cpp.

#include <map>
#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// Reads a VDB into a dense volume over the extinction grid's active bounding box (widened to the
/// box volstyle recorded when it wrote the file); other grids are resampled onto it when their
/// transform differs. The volume keeps the file (Volume::vdbSource) so saveVdb can write it back
/// losslessly. Throws IoError (missing, not a VDB, corrupt, truncated) or InvalidArgument (no
/// extinction grid, unsupported grid type, non-linear transform, values out of range, over `limits`).
Volume loadVdb(const std::string& path, const VolumeLimits& limits = {});

/// The frames of one VDB holding a whole animation: grids with an integer `frame` metadata entry,
/// or named with a frame number after a dot or underscore (`density.12`, `density_0012`,
/// `vel.12`), grouped by frame, each frame read as loadVdb reads a file (its grids renamed
/// without the number). Empty when no grid is stamped with a frame. Same errors as loadVdb, the
/// frame named.
std::map<int, Volume> loadVdbFrames(const std::string& path, const VolumeLimits& limits = {});

/// Writes a volume so that loadVdb gives it back bit for bit (so it renders the same).
/// A volume read from a file is written into that file's grids: an unchanged grid as it was, a
/// changed one as a copy with only the changed voxels rewritten (name, class, transform, metadata
/// and index space kept; a float grid becomes Vec3f only when the values stop being grey), and
/// every grid volstyle does not use, and the file's metadata, as they were. Otherwise the grids are
/// made sparse: voxels equal to the grid's background (albedo 1, others 0) are inactive, the rest
/// active leaf voxels — never tiles, which Blender's Cycles (3.4) renders as empty. Grey extinction
/// is float `density` (class fog volume), chromatic Vec3f `extinction`. Writes to a temporary file
/// and renames it into place.
void saveVdb(const std::string& path, const Volume& volume);

/// The velocity grid of a volume read from a VDB — `vel` (Houdini's name), `v` or `velocity`, a
/// Vec3f grid in world units per second — on the volume's voxels (3 per voxel); empty when the
/// file had none or the volume was not read from a file. Throws InvalidArgument for a velocity
/// grid that is not Vec3f or has non-finite values.
std::vector<float> velocityOf(const Volume& volume);

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
    std::vector<std::pair<std::string, std::string>> metadata;  ///< name, value as text
};

std::vector<VdbGridInfo> inspectVdb(const std::string& path);

/// What a round trip lost between two VDB files, a line each (empty: nothing): grids missing, value
/// types, classes, transforms, voxel sizes, grid and file metadata (not OpenVDB's `file_*`
/// statistics, recomputed on every write) and, with `values`, active index boxes, active voxels
/// and their values, bit for bit. Grids only `after` has are not differences.
std::vector<std::string> vdbDifferences(const std::string& before, const std::string& after, bool values = true);

/// The file-level metadata of a VDB (name, value as text).
std::vector<std::pair<std::string, std::string>> vdbFileMetadata(const std::string& path);

}  // namespace volstyle::core

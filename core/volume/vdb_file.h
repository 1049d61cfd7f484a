#pragma once
/// \file vdb_file.h
/// Internal to core/volume: reading a VDB file whole and a grid onto a volume's voxels (defined in
/// vdb_read.cpp), and what vdb_read.cpp, vdb_write.cpp and vdb_inspect.cpp share. Includes
/// OpenVDB: only those three translation units may include it.

#include <openvdb/openvdb.h>

#include <array>
#include <string>

#include "core/math/vec.h"
#include "core/volume/vdb_grid_roles.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// What a volume read from a file keeps of it (volume.h), so that saveVdb loses nothing.
struct VdbSource {
    openvdb::GridCPtrVec grids;  ///< every grid of the file in its order, as read (never modified)
    openvdb::MetaMap fileMetadata;
    std::array<openvdb::GridBase::ConstPtr, vdb_role::kRoleCount> roles;  ///< the grids read as each role
    openvdb::Coord origin;  ///< file index of the volume's voxel (0,0,0)
    Int3 dims;
    Mat4 worldFromIndex;  ///< the volume's transform as read
};

}  // namespace volstyle::core

namespace volstyle::core::vdb_file {

/// Metadata recording the dense box on the extinction grid when its active voxels do not span it
/// (a built-in cloud with empty borders): reading it back gives the same dims, hence the same render.
inline constexpr const char* kBoxMinKey = "volstyle_dense_box_min";
inline constexpr const char* kBoxMaxKey = "volstyle_dense_box_max";
/// The exact index-to-world matrix of a volume made in memory: OpenVDB's Transform simplifies
/// every linear map it is given (recomputing scales by subtraction), which may change the last
/// bit. Read back in place of the file's transform while that still agrees with it.
inline constexpr const char* kMatrixKey = "volstyle_world_from_index";


/// A name or path in single quotes, for messages.
inline std::string quoted(const std::string& s) { return "'" + s + "'"; }

/// Every grid of a file in its order, and the file's metadata.
struct FileContents {
    openvdb::GridCPtrVec grids;
    openvdb::MetaMap metadata;
};

/// Reads a whole file (not delay-loaded). Throws IoError naming what is wrong: missing, a folder,
/// unreadable, not a VDB, truncated, corrupt, or asking for more memory than it can need.
FileContents readVdbFile(const std::string& path);

/// Once per process, before anything else of OpenVDB.
void initOpenVdb();

/// OpenVDB matrices act on row vectors (p' = p·M); ours on column vectors: transpose.
inline Mat4 fromVdb(const openvdb::math::Mat4d& m) {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r(i, j) = m(j, i);
    return r;
}

/// Ours to OpenVDB's (the transpose).
inline openvdb::math::Mat4d toVdb(const Mat4& m) {
    openvdb::math::Mat4d r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r(j, i) = m(i, j);
    return r;
}

/// The shared transform of a grid (OpenVDB's Transform::copy() re-simplifies the map: lossy).
inline openvdb::math::Transform::Ptr sharedTransform(const openvdb::GridBase& grid) {
    return openvdb::ConstPtrCast<openvdb::math::Transform>(grid.constTransformPtr());
}

/// A float or Vec3f grid's values on the voxels `shape` stores (RGB; a float grid repeated), in its
/// storage order: voxel (i,j,k) being index `origin + (i,j,k)` of `reference`. Direct lookups (a
/// leaf a brick) when the transforms agree, trilinear world-space resampling otherwise. A sparse
/// shape's background brick holds the grid's background. Throws InvalidArgument for other types.
std::vector<float> readGrid(const openvdb::GridBase::ConstPtr& grid, const openvdb::GridBase& reference,
                            const openvdb::Coord& origin, const Volume& shape, const std::string& path);

/// readGrid for a role (an absent refractive index, 0, is vacuum: 1).
std::vector<float> readRole(vdb_role::Role role, const openvdb::GridBase::ConstPtr& grid, const openvdb::GridBase& reference,
                            const openvdb::Coord& origin, const Volume& shape, const std::string& path);

/// The grid named `name`, or null.
openvdb::GridBase::ConstPtr findGrid(const openvdb::GridCPtrVec& grids, const std::string& name);

}  // namespace volstyle::core::vdb_file

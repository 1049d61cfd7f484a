#pragma once
/// \file vdb_file.h
/// Internal to core/volume: reading a VDB file whole (defined in vdb_io.cpp), and what vdb_io.cpp
/// and vdb_inspect.cpp share. Includes OpenVDB: only those two translation units may include it.

#include <openvdb/openvdb.h>

#include <string>

#include "core/math/vec.h"

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

/// The grid named `name`, or null.
openvdb::GridBase::ConstPtr findGrid(const openvdb::GridCPtrVec& grids, const std::string& name);

}  // namespace volstyle::core::vdb_file

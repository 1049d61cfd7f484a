#pragma once
/// \file vdb_grid_roles.h
/// What the grids of a VDB file mean to volstyle, without OpenVDB: the role each grid plays in a
/// Volume, the names a role is read from and written as, what a voxel the file does not store is
/// worth, and the frame a grid's name stamps it with in a file that holds a whole animation.
/// vdb_read.cpp and vdb_write.cpp, the OpenVDB side, apply them.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/volume/volume.h"

namespace volstyle::core::vdb_role {

/// What a grid does in the volume.
enum Role { kExtinction, kAlbedo, kEmission, kRefractiveIndex, kRoleCount };

/// The names a role is read from, in order of preference (Houdini and Blender call extinction
/// `density`), and the name a grid made from scratch gets (grey extinction: `density`).
std::vector<std::string> roleNames(Role role);

/// What a voxel the file does not store is worth in the volume: albedo defaults to white, the
/// refractive index to vacuum, the rest to zero.
float absentValue(Role role);

/// The dense RGB grid of the volume for a role (the refractive index repeated in R, G and B).
std::vector<float> denseOfVolume(const Volume& v, Role role);

/// The largest frame number a grid's name or `frame` metadata may carry (the server allows fewer).
constexpr int kMaxGridFrame = 999999;

/// The frame a grid name ending in `.N` or `_N` (at most 6 digits, after at least one character)
/// stamps it with, and the name without the number; nothing for any other name. A name that
/// stamps a frame out of range (`density.-1`, `density.4294967301`) throws InvalidArgument
/// naming it: such a grid was once dropped in silence, or its number wrapped.
std::optional<std::pair<int, std::string>> frameOfGridName(const std::string& name);

}  // namespace volstyle::core::vdb_role

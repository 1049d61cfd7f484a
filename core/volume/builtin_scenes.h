#pragma once
/// \file builtin_scenes.h
/// Deterministic procedural volumes for demos and tests. Each spans the world box [-1, 1]³
/// (y up) with `resolution`³ voxels.

#include <string>
#include <vector>

#include "core/volume/glass_sphere.h"
#include "core/volume/volume.h"

namespace volstyle::core {

struct BuiltinSceneInfo {
    std::string name;
    std::string description;
};

constexpr int kMinSceneResolution = 8;   ///< tests use tiny grids; the CLI asks for 32–256
constexpr int kMaxSceneResolution = 256;
constexpr int kDefaultSceneResolution = 128;

/// cloud, plume, sphere, cube.
const std::vector<BuiltinSceneInfo>& builtinScenes();

/// Builds scene `name` at `resolution`³. Throws InvalidArgument for an unknown name (listing the
/// known ones) or a resolution outside [kMinSceneResolution, kMaxSceneResolution].
Volume makeBuiltinScene(const std::string& name, int resolution = kDefaultSceneResolution);

/// Sets `volume`'s refractive_index grid to `glass` (1 outside the sphere, so the box's faces do
/// not refract).
void addGlassSphere(Volume& volume, const GlassSphere& glass = {});

/// Index-to-world transform that maps `resolution`³ voxel centres into [-1, 1]³.
Mat4 unitBoxWorldFromIndex(Int3 dims);

}  // namespace volstyle::core

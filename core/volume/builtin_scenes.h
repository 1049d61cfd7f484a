#pragma once
/// \file builtin_scenes.h
/// Deterministic procedural volumes for demos and tests. Each spans the world box [-1, 1]³
/// (y up) with `resolution`³ voxels.

#include <string>
#include <vector>

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

/// A glass sphere for refraction (issue #16, the TVCG paper's Fig. 8).
struct GlassSphere {
    double index = 1.33;        ///< n inside
    double radius = 0.55;       ///< world units, centred on the volume's box
    double edgeVoxels = 2;      ///< width of the smooth step from 1 to `index` at the surface
    double noise = 0.03;        ///< amplitude of the Perlin noise added to n inside
    double noiseFrequency = 3;  ///< of the noise, per world unit
    uint32_t seed = 1;
};
/// Sets `volume`'s refractive_index grid to `glass` (1 outside the sphere, so the box's faces do
/// not refract).
void addGlassSphere(Volume& volume, const GlassSphere& glass = {});

/// Index-to-world transform that maps `resolution`³ voxel centres into [-1, 1]³.
Mat4 unitBoxWorldFromIndex(Int3 dims);

}  // namespace volstyle::core

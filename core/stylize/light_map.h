#pragma once
/// \file light_map.h
/// The stylizer's geometry, GL-free: where the light's shadow map lies (orthographic for a
/// directional light, perspective for a spot) over the occluders' bounds and how large its
/// texels are, the camera's clip transform, and what the per-object edits need from them (the
/// epipole of Eq. 3, the holes' noise frame of Eq. 4, the dilation's kernel in texels).

#include <utility>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/stylize/scene.h"
#include "core/stylize/shadow_edits.h"

namespace volstyle::core {

/// World-space bounds of an occluder after its transform.
std::pair<Vec3d, Vec3d> occluderBounds(const Occluder& o);

/// The perspective map of a spot light at `position` shining along −towardLight with a full cone
/// of `coneDeg` (the map's square circumscribes the cone), deep enough for the bounds [lo, hi].
Mat4 spotClipFromWorld(const Vec3d& position, const Vec3d& towardLight, double coneDeg, const Vec3d& lo, const Vec3d& hi);

/// The orthographic map from world space to the light's clip space [-1,1]³ that covers the
/// world-space bounds [lo, hi] seen from `towardLight` (near plane on the light's side), leaving
/// `marginTexels` of an n-texel map empty around them (closings then never reach the border).
Mat4 lightClipFromWorld(const Vec3d& towardLight, const Vec3d& lo, const Vec3d& hi, int n = 2048, int marginTexels = 0);

/// The light's shadow map for a scene: its clip transform over the occluders' bounds, and the
/// world size of a texel (for a spot: per unit of distance from it).
struct LightMap {
    Vec3d lo, hi;
    std::vector<std::pair<Vec3d, Vec3d>> objectBounds;  ///< each occluder's world bounds (one pass over its vertices)
    Mat4 clip;
    bool spot = false;
    double spotTan = 0, texel = 0;
};
LightMap lightMapOf(const StylizerScene& scene);

/// Eq. 3's kernel for occluder `i`, in texels where the object is (a spot's grow with distance).
int dilationTexels(const LightMap& map, const StylizerScene& scene, size_t i);

/// The camera's epipole in an n-texel map (Eq. 3's dilation runs away from it).
Epipole epipoleOf(const Mat4& lightClip, const Vec3d& eye, int n);
/// The holes' noise frame in the map: `frequency` cycles per world unit across the beams
/// (`spotScale`: a spot's world size per unit of its clip coordinates where the object is).
HoleMap holeMapOf(const Mat4& lightClip, bool spot, double spotScale, int n, double frequency);

/// An OpenGL perspective projection, and the camera's from world space.
Mat4 perspective(double tanHalfY, double aspect, double nearDist, double farDist);
Mat4 cameraClipFromWorld(const Camera& cam, double nearDist, double farDist);

}  // namespace volstyle::core

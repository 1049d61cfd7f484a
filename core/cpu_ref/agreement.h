#pragma once
/// \file agreement.h
/// How closely a render agrees with a reference, as the light-depth tests and benchmark state it
/// (issue #34), and the built-in scenes made as dense as those checks need.

#include <cmath>

#include "core/image/image.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/volume.h"

namespace volstyle::core::cpu_ref {

/// The sum of `image` over the sum of `reference` (RGB), and the RMS of their difference over the
/// RMS of `reference`.
struct Agreement {
    double sumRatio, relativeRms;
};

inline Agreement agreement(const Image& image, const Image& reference) {
    double sum = 0, refSum = 0, num = 0, den = 0;
    for (size_t i = 0; i < reference.pixelCount(); ++i)
        for (size_t c = 0; c < 3; ++c) {
            const double x = image.rgba[4 * i + c], y = reference.rgba[4 * i + c];
            sum += x, refSum += y, num += (x - y) * (x - y), den += y * y;
        }
    return {sum / refSum, std::sqrt(num / den)};
}

/// Scales `volume`'s extinction so that its densest voxel holds `voxelDepth` optical depths
/// (along an index-space x edge).
inline void scaleToVoxelDepth(Volume& volume, double voxelDepth) {
    const double peak = maxComponent(Volume::range(volume.extinction()).second);
    const double voxel = length(volume.worldFromIndex().applyVector({1, 0, 0}));
    for (float& s : volume.extinction()) s = float(s * voxelDepth / (peak * voxel));
}

/// Built-in scene `name` at `res`³, scaled so that its densest voxel holds `voxelDepth` optical
/// depths (0: as it is), with albedo 0.9: the dense media the light-depth checks use.
inline Volume denseBuiltinScene(const char* name, int res, double voxelDepth) {
    Volume v = makeBuiltinScene(name, res);
    if (voxelDepth > 0) scaleToVoxelDepth(v, voxelDepth);
    for (float& a : v.ensureAlbedo()) a = 0.9f;
    return v;
}

}  // namespace volstyle::core::cpu_ref

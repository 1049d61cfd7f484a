#pragma once
/// \file perturbation.h
/// Volume perturbation (Kniss et al. 2003, Sec. 3.4; SPEC §9): a small periodic noise volume
/// (kNoiseSize³, four random channels, slightly blurred) read at several scales. Three channels
/// displace where the volume is looked up (detail that a coarse grid cannot hold); the fourth
/// modulates its extinction. Animated by `time` (each octave drifts, so nothing pops). The same
/// field is evaluated by the translucent renderer's shader (at render time) and here (to bake it
/// into a volume). GL-free.

#include <cstdint>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/shaders/layout.h"
#include "core/volume/volume.h"

namespace volstyle::core {

constexpr int kNoiseSize = layout::kNoiseSize;

struct Perturbation {
    double amplitude = 0;          ///< largest displacement of the lookups, in voxels (>= 0; 0: none)
    double frequency = 8;          ///< the first octave's noise features (texels) across the volume's longest side, (0, 256]
    int octaves = 3;               ///< each twice the frequency and half the amplitude of the last, 1–6
    double propertyAmplitude = 0;  ///< extinction scaled by 1 + a·n, n in [-1, 1] ([0, 1]; 0: none)
    uint32_t seed = 1;             ///< which noise
    double time = 0;               ///< animation time (any finite value)

    bool active() const { return amplitude > 0 || propertyAmplitude > 0; }
    std::vector<FieldProblem> check() const;  ///< fields as in JSON: "amplitude", "octaves", …
};

/// The noise volume of `seed`: kNoiseSize³ texels × 4 channels (RGBA, x fastest) in [0, 1],
/// periodic, blurred by a 3-tap box in each axis.
std::vector<float> noiseTexels(uint32_t seed);

/// The perturbation field over a volume's index space (voxel centres at integers).
class PerturbationField {
public:
    PerturbationField(const Perturbation& p, Int3 volumeDims);
    /// Where the volume is read instead of index point p: p + displacement (voxels).
    Vec3d displacement(const Vec3d& p) const;
    /// The extinction's factor at p: max(0, 1 + propertyAmplitude · n(p)).
    double extinctionScale(const Vec3d& p) const;
    /// Noise texels per voxel for octave 0, and each octave's drift per unit time (texels).
    double texelsPerVoxel() const { return m_texelsPerVoxel; }
    static Vec3d drift(int octave);

private:
    /// The four channels, each in [-1, 1], summed over the octaves (weights 1/2^o, normalised).
    Vec3d noise(const Vec3d& p, double& fourth) const;
    Perturbation m_p;
    std::vector<float> m_texels;
    double m_texelsPerVoxel = 1;
};

/// `volume` with the perturbation baked in: every grid read where the field displaces it
/// (trilinear), the extinction scaled. The result has the volume's dims and transform; a sparse
/// volume stays sparse, its bricks grown by the displacement's reach (issue #39).
Volume perturbVolume(const Volume& volume, const Perturbation& p);

}  // namespace volstyle::core

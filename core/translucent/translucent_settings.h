#pragma once
/// \file translucent_settings.h
/// The translucent preview's parameters (SPEC §9; Kniss et al. 2003, Sec. 3, Eq. 9–12), named after
/// the paper's. GL-free: the protocol validates requests against check().

#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/translucent/perturbation.h"

namespace volstyle::core {

/// Forward-scattered indirect light (Sec. 3.3): light carried from slice to slice, blurred over a
/// cone and attenuated less than the direct light, turning the transport colour as it goes.
struct IndirectLight {
    bool enabled = true;
    /// θ, the cone's apex angle: each slice gathers the previous slice's light within
    /// d·tan(θ/2) of its own position (Eq. 9). [0, 90).
    double blurAngleDeg = 30;
    /// Indirect extinction per unit of the volume's extinction (σ_i = k σt): below 1 indirect light
    /// reaches deeper than direct light. >= 0.
    double extinction = 0.35;
    /// The colour indirect light becomes per unit of indirect optical depth (the paper's transport
    /// colour, 1 − indirect alpha, Fig. 7): RGB in (0, 1].
    Vec3d transportColor{1.0, 0.78, 0.55};
};

struct TranslucentSettings {
    /// Distance between slices along the half-angle axis, in voxels (the slice count follows it
    /// and the volume's extent). (0, 8].
    double sliceSpacing = 1.0;
    /// Texels of the light buffers along each side (the light's view of the volume). [16, 4096].
    int lightBufferSize = 512;
    IndirectLight indirect;
    /// S (Eq. 11): 0 shades by light attenuation only, 1 fully Blinn–Phong from the extinction's
    /// gradient (surface-like media). [0, 1].
    double surfaceShading = 0;
    /// Noise detail at render time (Sec. 3.4; perturbation.h); inactive by default.
    Perturbation perturbation;

    std::vector<FieldProblem> check() const;
    void validate() const;  ///< throws InvalidArgument listing check()'s problems
};

}  // namespace volstyle::core

#pragma once
/// \file solve_types.h
/// GL-free names of what the solver solves for (SPEC §2). The values are the constants the
/// shaders compile against (core/shaders/layout.h), so C++ and GLSL agree by construction.

#include "core/shaders/layout.h"

namespace volstyle::core {

/// The unknown field (TVCG Sec. 4.2.1–4.2.4), VOLSTYLE_UNKNOWN in project.comp.
enum class Unknown {
    Emission = VOLSTYLE_UNKNOWN_EMISSION,
    Albedo = VOLSTYLE_UNKNOWN_ALBEDO,
    EmissionAlbedo = VOLSTYLE_UNKNOWN_EMISSION_ALBEDO,
    Extinction = VOLSTYLE_UNKNOWN_EXTINCTION,
};

/// Basis functions of the unknown grid: box (nearest voxel) or trilinear (hat functions),
/// VOLSTYLE_BASIS in project.comp.
enum class BasisType { Box = VOLSTYLE_BASIS_BOX, Trilinear = VOLSTYLE_BASIS_TRILINEAR };

static_assert(int(Unknown::Emission) == VOLSTYLE_UNKNOWN_EMISSION && int(Unknown::Extinction) == VOLSTYLE_UNKNOWN_EXTINCTION);
static_assert(int(BasisType::Trilinear) == VOLSTYLE_BASIS_TRILINEAR);

}  // namespace volstyle::core

#pragma once
/// \file basis.h
/// Basis functions of a grid of values: box (nearest voxel) or trilinear (hat functions at voxel
/// centres). Volumes are resampled with them (resample.h) and the solver's unknowns use them
/// (solve_types.h), so the type lives with the volume, not above it. The values are the constants
/// the shaders compile against (core/shaders/layout.h), VOLSTYLE_BASIS in project.comp.

#include "core/shaders/layout.h"

namespace volstyle::core {

enum class BasisType { Box = VOLSTYLE_BASIS_BOX, Trilinear = VOLSTYLE_BASIS_TRILINEAR };

static_assert(int(BasisType::Trilinear) == VOLSTYLE_BASIS_TRILINEAR);

}  // namespace volstyle::core

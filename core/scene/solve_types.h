#pragma once
/// \file solve_types.h
/// GL-free names of what the solver solves for (SPEC §2). The values are the constants the
/// shaders compile against (core/shaders/layout.h), so C++ and GLSL agree by construction.

#include "core/shaders/layout.h"
#include "core/volume/basis.h"  // BasisType: the unknown grid's basis

namespace volstyle::core {

/// The unknown field (TVCG Sec. 4.2.1–4.2.4), VOLSTYLE_UNKNOWN in project.comp.
enum class Unknown {
    Emission = VOLSTYLE_UNKNOWN_EMISSION,
    Albedo = VOLSTYLE_UNKNOWN_ALBEDO,
    EmissionAlbedo = VOLSTYLE_UNKNOWN_EMISSION_ALBEDO,
    Extinction = VOLSTYLE_UNKNOWN_EXTINCTION,
};

static_assert(int(Unknown::Emission) == VOLSTYLE_UNKNOWN_EMISSION && int(Unknown::Extinction) == VOLSTYLE_UNKNOWN_EXTINCTION);

}  // namespace volstyle::core

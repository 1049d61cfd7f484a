#pragma once
/// \file solve_types.h
/// GL-free names of what the solver solves for (SPEC §2).

namespace volstyle::core {

/// The unknown field (TVCG Sec. 4.2.1–4.2.4). The values match VOLSTYLE_UNKNOWN in project.comp.
enum class Unknown { Emission = 1, Albedo = 2, EmissionAlbedo = 3, Extinction = 4 };

/// Basis functions of the unknown grid: box (nearest voxel) or trilinear (hat functions).
enum class BasisType { Box = 0, Trilinear = 1 };

}  // namespace volstyle::core

#pragma once
// The extinction solve from masks (TVCG Sec. 4.2.4) as the solver and refraction tests set it up:
// a constant medium radiance L_m emitted everywhere, no lights, extinction solved from zero.
#include "core/scene/solve_options.h"
#include "core/volume/volume.h"

namespace volstyle::test {

/// Sets every voxel's emission to Lm (the medium radiance the masks assume).
inline void fillEmission(core::Volume& v, const Vec3d& Lm) {
    auto& e = v.ensureEmission();
    for (size_t i = 0; i < v.voxelCount(); ++i) e[3 * i] = float(Lm.x), e[3 * i + 1] = float(Lm.y), e[3 * i + 2] = float(Lm.z);
}

/// `truth` with its extinction zeroed, and the options of an 80-iteration extinction solve.
inline std::pair<core::Volume, core::SolveOptions> maskSolve(const core::Volume& truth, const Vec3d& Lm) {
    core::Volume start = truth;
    start.extinction().assign(start.voxelCount() * 3, 0.0f);
    core::SolveOptions opt;
    opt.unknown = core::Unknown::Extinction;
    opt.mediumRadiance = Lm;
    opt.maxIterations = 80;
    opt.tolerance = 1e-6;
    return {std::move(start), opt};
}

}  // namespace volstyle::test

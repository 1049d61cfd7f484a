#pragma once
// A known low-frequency environment for the light-reconstruction tests (issue #13): a warm key
// from the upper left front, a blue sky from above and a dim green bounce from below, as the
// radiances of a lobe basis.
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/scene/environment_lobes.h"

namespace volstyle::test {

inline std::vector<Vec3d> threeColourSky(const core::LobeBasis& basis) {
    std::vector<Vec3d> c;
    for (const Vec3d& d : basis.directions) {
        const double key = std::pow(std::max(0.0, dot(d, normalize(Vec3d(-0.6, 0.6, 0.5)))), 2);
        const double sky = std::max(0.0, d.y), bounce = std::max(0.0, -d.y);
        c.push_back(Vec3d(2.0, 1.5, 0.9) * key + Vec3d(0.3, 0.5, 0.9) * sky + Vec3d(0.1, 0.25, 0.1) * bounce);
    }
    return c;
}

}  // namespace volstyle::test

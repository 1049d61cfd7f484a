#pragma once
// The synthetic ground truth of the solver's recovery tests and benchmark: the built-in cloud,
// thinned so its inside shows, with "VS" stamped into a property.
#include <cmath>
#include <vector>

#include "core/volume/builtin_scenes.h"

namespace volstyle::test {

/// "VS" in a 5x7-cell font over the x–y plane, extruded along z.
inline bool inLetters(const Vec3d& w) {
    static const char* glyphs[5] = {"X.X.XXX", "X.X.X..", "X.X.XXX", "X.X...X", ".X..XXX"};
    int col = int(std::floor((w.x + 0.7) / 1.4 * 7)), row = int(std::floor((0.55 - w.y) / 1.1 * 5));
    return col >= 0 && col < 7 && row >= 0 && row < 5 && glyphs[row][col] == 'X';
}

/// Sets `grid` (RGB, 3 floats per voxel of `v`) to `rgb` at every voxel inside the letters.
inline void stampLetters(const core::Volume& v, std::vector<float>& grid, Vec3 rgb) {
    const Int3 n = v.dims();
    for (int k = 0; k < n.z; ++k)
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i)
                if (inLetters(v.worldFromIndex().applyPoint({double(i), double(j), double(k)}))) {
                    size_t idx = 3 * v.index(i, j, k);
                    grid[idx] = rgb.x, grid[idx + 1] = rgb.y, grid[idx + 2] = rgb.z;
                }
}

/// The built-in cloud at `res`³ with its extinction scaled to an optical depth of a few units.
inline core::Volume thinCloud(int res) {
    core::Volume v = core::makeBuiltinScene("cloud", res);
    for (float& s : v.extinction()) s *= 0.08f;
    return v;
}

}  // namespace volstyle::test

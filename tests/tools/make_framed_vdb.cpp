// Writes the built-in cloud (32³) as a VDB of `size` world units a side centred at (cx, cy, cz),
// its extinction scaled so it is as opaque as the unit-box cloud: an artist's asset off the
// origin, huge or tiny (issue #37's framing test, tests/web/e2e_frame.cjs).
// Usage: make_framed_vdb OUT.vdb SIZE CX CY CZ
#include <cstdio>
#include <cstdlib>

#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"

using namespace volstyle;
using namespace volstyle::core;

int main(int argc, char** argv) {
    if (argc != 6) {
        std::fprintf(stderr, "usage: make_framed_vdb OUT.vdb SIZE CX CY CZ\n");
        return 2;
    }
    const double size = std::atof(argv[2]);
    const Vec3d centre{std::atof(argv[3]), std::atof(argv[4]), std::atof(argv[5])};
    const int n = 32;
    Volume cloud = makeBuiltinScene("cloud", n);
    const double h = size / n;  // the built-in box is 2 units a side
    cloud.setWorldFromIndex(Mat4::translate(centre - Vec3d(size / 2 - h / 2)) * Mat4::scale(Vec3d(h)));
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const Vec3 e = cloud.extinctionAt(i, j, k);
                const float s = float(2.0 / size);  // the same optical depth across the box
                cloud.setExtinction(i, j, k, {e.x * s, e.y * s, e.z * s});
            }
    saveVdb(argv[1], cloud);
    return 0;
}

// Writes a smoke plume as a simulation would (issue #39): in an NX×NY×NZ box (1024 512 1024 is
// the Houdini-sized sim, about 3% active), a column rising from the ground and bending
// downwind, widening as it rises, its edge broken up by noise; float `density` (fog volume) and
// `temperature` (falls with height) and Vec3f `vel` (along the column), leaf voxels on background 0.
// Usage: make_plume_vdb OUT.vdb [NX NY NZ [WIDTH [FRAME]]]   (WIDTH scales the column's radius:
// activity ∝ WIDTH²; FRAME, default 0, moves the smoke's noise up along the column as 24 fps of its
// velocity would, and sways the column: a sequence of frames on one box for `volstyle animate`)
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/volume/noise.h"

using namespace volstyle;
using namespace volstyle::core;

int main(int argc, char** argv) {
    if (argc != 2 && (argc < 5 || argc > 7)) {
        std::fprintf(stderr, "usage: make_plume_vdb OUT.vdb [NX NY NZ [WIDTH [FRAME]]]\n");
        return 2;
    }
    const int nx = argc >= 5 ? std::atoi(argv[2]) : 1024, ny = argc >= 5 ? std::atoi(argv[3]) : 512, nz = argc >= 5 ? std::atoi(argv[4]) : 1024;
    const double width = argc >= 6 ? std::atof(argv[5]) : 1.0;
    const int frame = argc == 7 ? std::atoi(argv[6]) : 0;
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto temperature = openvdb::FloatGrid::create(0.0f);
    temperature->setName("temperature");
    auto vel = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    vel->setName("vel");
    vel->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    auto xf = openvdb::math::Transform::createLinearTransform(20.0 / nx);  // 20 m wide whatever the resolution
    for (auto g : {openvdb::GridBase::Ptr(density), openvdb::GridBase::Ptr(temperature), openvdb::GridBase::Ptr(vel)}) g->setTransform(xf);
    auto d = density->getAccessor();
    auto t = temperature->getAccessor();
    auto v = vel->getAccessor();
    const PerlinNoise noise(3);
    // In units of the 1024×512×1024 box, scaled to this one: the column's centre at height h and its radius.
    const double sx = nx / 1024.0, sy = ny / 512.0, sz = nz / 1024.0;
    auto centre = [&](double h) { return Vec3d(sx * (200 + 600 * std::pow(h / 512, 2.0)), sy * h, sz * (512 + 60 * std::sin(h / 90 - 0.05 * frame))); };
    // The noise rises 2 m/s / 24 fps a frame (vel below), in voxels of this box (20 m wide).
    const Vec3d rise(0, frame * (2.0 / 24) / (20.0 / nx), 0);
    auto radius = [&](double h) { return width * sx * (42 + 105 * h / 512); };
    for (int y = 0; y < ny; ++y) {
        const double h = y / sy;
        const Vec3d c = centre(h);
        const double r = radius(h), reach = r * 1.35;
        const Vec3d along = normalize(centre(h + 1) - c);
        for (int z = int(c.z - reach); z <= int(c.z + reach); ++z)
            for (int x = int(c.x - reach); x <= int(c.x + reach); ++x) {
                const Vec3d p(x, y, z);
                const double dist = std::hypot(p.x - c.x, p.z - c.z);
                if (dist > reach || x < 0 || x >= nx || z < 0 || z >= nz) continue;
                const double edge = dist / r + 0.35 * noise.fbm((p - rise) * (1.0 / (40 * sx)), 3);
                if (edge >= 1) continue;
                const openvdb::Coord ijk(x, y, z);
                d.setValue(ijk, float(0.6 * (1 - edge) * (1 - 0.5 * h / 512) / sx));  // the same optical depth at any resolution
                t.setValue(ijk, float(1.5 * (1 - edge) * (1 - h / 512)));
                v.setValue(ijk, openvdb::Vec3s(float(along.x * 2), float(along.y * 2), float(along.z * 2)));
            }
    }
    // The sim's box, as a simulation container records it: the bottom corner and the far top corner.
    d.setValue(openvdb::Coord(0, 0, 0), 0.0f), d.setValue(openvdb::Coord(nx - 1, ny - 1, nz - 1), 0.0f);
    openvdb::io::File(argv[1]).write({density, temperature, vel});
    std::printf("%s: %dx%dx%d, %llu active density voxels (%.2f%% of the box)\n", argv[1], nx, ny, nz,
                (unsigned long long)density->activeVoxelCount(), 100.0 * double(density->activeVoxelCount()) / (double(nx) * ny * nz));
    return 0;
}

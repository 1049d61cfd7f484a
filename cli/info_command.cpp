// `volstyle info FILE.vdb`: the grids of a VDB file — names, types, dimensions, transform and
// value ranges — and whether volstyle can load it.

#include <fmt/format.h>

#include <iostream>

#include "core/base/errors.h"
#include "core/volume/vdb_io.h"
#include "cli/cli.h"

namespace volstyle::cli {

namespace {
const CommandSpec kInfo{"info", "describe a VDB file and whether volstyle loads it", "FILE.vdb",
                        "Lists a VDB's grids (name, type, class, active voxels and index box, voxel size, transform,\n"
                        "value range, metadata) and the file's metadata, and says whether volstyle can load it.",
                        {},
                        "  volstyle info smoke.vdb\n"};
}  // namespace

const CommandSpec& infoCommand() { return kInfo; }

int runInfo(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, kInfo);
    if (printHelpIfAsked(args, kInfo)) return 0;
    if (args.positional.size() != 1) throw InvalidArgument("expected one FILE.vdb (volstyle info --help)");
    const std::string path = args.positional[0];
    auto grids = core::inspectVdb(path);
    std::cout << path << ": " << grids.size() << " grid(s)\n";
    for (const auto& [key, value] : core::vdbFileMetadata(path)) std::cout << "  file metadata " << key << " = " << value << "\n";
    for (const auto& g : grids) {
        // In 64 bits: an empty grid's box is [INT_MAX, INT_MIN] (UBSan caught the overflow), and a
        // damaged one may span ±2e9. A grid whose every voxel is its background has none active.
        int64_t dims[3] = {0, 0, 0};
        if (g.activeVoxels > 0)
            for (int a = 0; a < 3; ++a) dims[a] = int64_t(g.activeMax[a]) - int64_t(g.activeMin[a]) + 1;
        std::cout << fmt::format("  {:<18} {:<6} {:<10} active voxels {:>10}  bbox [{} {} {}]..[{} {} {}]  dims {}x{}x{}\n",
                                 g.name, g.type, g.gridClass, g.activeVoxels, g.activeMin.x, g.activeMin.y,
                                 g.activeMin.z, g.activeMax.x, g.activeMax.y, g.activeMax.z, dims[0], dims[1], dims[2]);
        std::cout << fmt::format("    voxel size [{:g} {:g} {:g}]", g.voxelSize.x, g.voxelSize.y, g.voxelSize.z);
        if (g.isLinearTransform) {
            const Mat4& m = g.worldFromIndex;
            std::cout << fmt::format("  world from index [[{:g} {:g} {:g} {:g}] [{:g} {:g} {:g} {:g}] [{:g} {:g} {:g} {:g}]]",
                                     m(0, 0), m(0, 1), m(0, 2), m(0, 3), m(1, 0), m(1, 1), m(1, 2), m(1, 3),
                                     m(2, 0), m(2, 1), m(2, 2), m(2, 3));
        } else {
            std::cout << "  non-linear (frustum) transform";
        }
        std::cout << "\n";
        if (g.type == "float")
            std::cout << fmt::format("    values [{:g}, {:g}]\n", g.minValue.x, g.maxValue.x);
        else
            std::cout << fmt::format("    values [{:g} {:g} {:g}] .. [{:g} {:g} {:g}]\n", g.minValue.x, g.minValue.y,
                                     g.minValue.z, g.maxValue.x, g.maxValue.y, g.maxValue.z);
        for (const auto& [key, value] : g.metadata)
            if (key.rfind("file_", 0) != 0 && key != "name" && key != "class")  // OpenVDB's own statistics
                std::cout << "    metadata " << key << " = " << value << "\n";
    }
    try {
        core::Volume v = core::loadVdb(path);
        std::cout << fmt::format("loads as a {}x{}x{} volume with {}{}\n", v.dims().x, v.dims().y, v.dims().z,
                                 v.hasAlbedo() ? "albedo" : "default albedo 1",
                                 v.hasEmission() ? ", emission" : ", no emission");
    } catch (const InvalidArgument& e) {
        std::cout << "does not load: " << e.what() << "\n";
        return 1;
    }
    return 0;
}

}  // namespace volstyle::cli

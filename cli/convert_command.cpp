// `volstyle convert IN.vdb OUT.vdb`: reads a VDB as volstyle does (every check of an upload), writes
// it as volstyle writes volumes, and verifies that nothing was lost on the way: a pipeline's test
// that its files survive volstyle (issue #10).

#include <iostream>

#include "core/volume/vdb_io.h"
#include "cli/cli.h"

namespace volstyle::cli {

namespace {
const CommandSpec kConvert{
    "convert",
    "rewrite a VDB as volstyle does and verify nothing is lost",
    "IN.vdb OUT.vdb",
    "Reads IN as volstyle reads a volume (the checks an upload gets), writes it to OUT as volstyle\n"
    "writes volumes, and verifies the round trip: every grid (also those volstyle does not use),\n"
    "its name, value type, class, transform, voxel size, metadata, active voxels and values, and the\n"
    "file's metadata. Exit status 0: lossless; 1: something was lost (listed); 2: IN is unusable.",
    {},
    "  volstyle convert smoke.vdb smoke-checked.vdb\n"};
}  // namespace

const CommandSpec& convertCommand() { return kConvert; }

int runConvert(const std::vector<std::string>& argv) {
    Arguments args = parseArguments(argv, kConvert);
    if (printHelpIfAsked(args, kConvert)) return 0;
    if (args.positional.size() != 2) throw InvalidArgument("expected IN.vdb and OUT.vdb (volstyle convert --help)");
    const std::string& in = args.positional[0];
    const std::string& out = args.positional[1];
    requireParentFolder(out);
    core::Volume volume = core::loadVdb(in);
    core::saveVdb(out, volume);
    const auto lost = core::vdbDifferences(in, out);
    const auto grids = core::inspectVdb(out);
    if (lost.empty()) {
        std::cout << "wrote " << out << ": " << grids.size() << " grid(s), " << volume.dims().x << "x" << volume.dims().y
                  << "x" << volume.dims().z << " voxels as volstyle reads it; lossless (grids, types, classes, "
                  << "transforms, metadata, active voxels and values all kept)\n";
        return 0;
    }
    std::cout << "wrote " << out << ", but the round trip lost:\n";
    for (const auto& line : lost) std::cout << "  " << line << "\n";
    return 1;
}

}  // namespace volstyle::cli

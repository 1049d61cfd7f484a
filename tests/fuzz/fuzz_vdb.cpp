// libFuzzer harness: an uploaded OpenVDB file read as `volstyle read-vdb` reads it (the child
// process that reads every upload, server/runtime/vdb_reader.h): loadVdb under the volume limits. Our code
// must refuse damaged files with a volstyle error; crashes inside OpenVDB itself are what the
// child process contains (scripts/fuzz.sh reports them apart).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "core/base/errors.h"
#include "core/volume/vdb_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string path = "/tmp/volstyle-fuzz-vdb-" + std::to_string(::getpid()) + ".vdb";
    if (FILE* f = std::fopen(path.c_str(), "wb")) {
        std::fwrite(data, 1, size, f);
        std::fclose(f);
    }
    volstyle::core::VolumeLimits limits;
    limits.maxVoxels = 64 * 64 * 64;
    try {
        volstyle::core::loadVdb(path, limits);
    } catch (const volstyle::Error&) {
    }
    return 0;
}

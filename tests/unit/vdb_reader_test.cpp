// Uploaded VDBs are read in a child process first (server/runtime/vdb_reader.h): a reader that crashes or
// hangs is a refused file, not a dead server; the child's refusals keep their kind and message.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "core/base/errors.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"
#include "server/runtime/vdb_reader.h"

using namespace volstyle;
namespace fs = std::filesystem;

namespace {

/// A stand-in reader: a shell script with `body`.
std::string fakeReader(const std::string& name, const std::string& body) {
    const fs::path p = fs::temp_directory_path() / ("volstyle-fake-reader-" + name);
    std::ofstream(p) << "#!/bin/sh\n" << body << "\n";
    ::chmod(p.c_str(), 0755);
    return p.string();
}

}  // namespace

TEST(VdbReader, AReaderThatCrashesIsARefusedFileNotACrash) {
    server::VdbReaderOptions reader;
    reader.executable = fakeReader("crash", "kill -SEGV $$");
    try {
        loadUntrustedVdb("upload.vdb", {}, reader);
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("crashed the VDB reader (signal 11"), std::string::npos) << e.what();
    }
}

TEST(VdbReader, AReaderPastItsTimeIsStopped) {
    server::VdbReaderOptions reader;
    reader.executable = fakeReader("hang", "exec sleep 30");
    reader.seconds = 0.5;
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_THROW(loadUntrustedVdb("upload.vdb", {}, reader), InvalidArgument);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
}

TEST(VdbReader, TheChildsRefusalsKeepTheirKindAndMessage) {
    server::VdbReaderOptions reader;
    reader.executable = VOLSTYLE_BINARY;
    const fs::path dir = fs::temp_directory_path() / "volstyle-reader-test";
    fs::create_directories(dir);
    const std::string good = (dir / "good.vdb").string(), junk = (dir / "junk.vdb").string();
    core::saveVdb(good, core::makeBuiltinScene("sphere", 12));
    std::ofstream(junk) << "not a vdb at all";
    // The reader crops to the active voxels, as the in-process loader does.
    EXPECT_EQ(loadUntrustedVdb(good, {}, reader).dims(), core::loadVdb(good).dims());
    core::VolumeLimits small;
    small.maxVoxels = 500;
    small.storage = core::VolumeStorage::Dense;  // (automatic storage would read it sparse)
    try {
        loadUntrustedVdb(good, small, reader);
        FAIL() << "expected LimitExceeded";
    } catch (const LimitExceeded& e) {
        EXPECT_NE(std::string(e.what()).find("500"), std::string::npos) << e.what();
    }
    EXPECT_THROW(loadUntrustedVdb(junk, {}, reader), Error);
    fs::remove_all(dir);
}

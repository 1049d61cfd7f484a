#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <sys/resource.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "core/base/errors.h"
#include "core/volume/vdb_io.h"
#include "test_files.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A volume with every voxel non-zero (so the active box is the whole grid) and a transform
/// with rotation, anisotropic scale and translation.
Volume randomVolume(Int3 dims, bool grey, uint32_t seed) {
    Mat4 rot;  // 30° about y
    double c = std::cos(0.5235987755982988), s = std::sin(0.5235987755982988);
    rot(0, 0) = c, rot(0, 2) = s, rot(2, 0) = -s, rot(2, 2) = c;
    Mat4 xf = Mat4::translate({0.3, -1.25, 2.0}) * rot * Mat4::scale({0.1, 0.05, 0.2});
    Volume v(dims, xf);
    std::mt19937 rng(seed);
    auto u = [&] { return 0.05f + float(rng() % 10000) / 10000.0f; };
    for (size_t i = 0; i < v.voxelCount(); ++i) {
        float g = u() * 5;
        for (int ch = 0; ch < 3; ++ch) v.extinction()[3 * i + ch] = grey ? g : u() * 5;
    }
    for (float& a : v.ensureAlbedo()) a = std::min(1.0f, u());
    for (float& e : v.ensureEmission()) e = u() * 3;
    return v;
}

void expectSameTransform(const Mat4& a, const Mat4& b) {
    for (int i = 0; i < 16; ++i) EXPECT_NEAR(a.m[size_t(i)], b.m[size_t(i)], 1e-12) << i;
}

}  // namespace

TEST(VdbIo, RoundTripKeepsValuesAndTransform) {
    auto dir = test::scratchDir();
    for (bool grey : {true, false}) {
        Volume v = randomVolume({9, 7, 11}, grey, grey ? 1 : 2);
        std::string path = (dir / (grey ? "grey.vdb" : "rgb.vdb")).string();
        saveVdb(path, v);
        Volume back = loadVdb(path);
        ASSERT_EQ(back.dims(), v.dims());
        expectSameTransform(back.worldFromIndex(), v.worldFromIndex());
        EXPECT_EQ(back.extinction(), v.extinction());  // float32 in, float32 out: bit exact
        EXPECT_EQ(back.albedo(), v.albedo());
        EXPECT_EQ(back.emission(), v.emission());
        std::set<std::string> names;
        for (const auto& g : inspectVdb(path)) names.insert(g.name);
        EXPECT_EQ(names, (std::set<std::string>{grey ? "density" : "extinction", "albedo", "emission"}));
    }
}

TEST(VdbIo, SparseWriteKeepsActiveVoxelsAsLeavesNotTiles) {
    auto dir = test::scratchDir();
    // A constant 16³ block inside a zero 32³ grid: pruning would turn it into a tile.
    Volume v({32, 32, 32}, Mat4::scale(Vec3d(0.5)));
    for (int k = 8; k < 24; ++k)
        for (int j = 8; j < 24; ++j)
            for (int i = 8; i < 24; ++i) v.setExtinction(i, j, k, Vec3(3.0f));
    const std::string path = (dir / "block.vdb").string();
    saveVdb(path, v);

    openvdb::io::File file(path);
    file.open();
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
    file.close();
    EXPECT_EQ(grid->activeVoxelCount(), 16u * 16 * 16);
    EXPECT_EQ(grid->tree().activeTileCount(), 0u) << "active values must be voxels (Blender renders tiles empty)";
    EXPECT_EQ(grid->tree().activeLeafVoxelCount(), 16u * 16 * 16);

    // Loading gives the active box back, with the transform shifted to its corner.
    Volume back = loadVdb(path);
    EXPECT_EQ(back.dims(), (Int3{16, 16, 16}));
    Vec3d corner = back.worldFromIndex().applyPoint({0, 0, 0});
    EXPECT_NEAR(corner.x, 4.0, 1e-12);  // voxel 8 at 0.5 per voxel
}

TEST(VdbIo, MissingExtinctionGridNamesTheGridsPresent) {
    auto dir = test::scratchDir();
    auto grid = openvdb::FloatGrid::create();
    grid->setName("temperature");
    grid->tree().setValue(openvdb::Coord(1, 2, 3), 1.0f);
    openvdb::io::File(( dir / "t.vdb").string()).write({grid});
    try {
        loadVdb((dir / "t.vdb").string());
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("grids present: temperature"), std::string::npos) << e.what();
    }
}

TEST(VdbIo, NanAndNegativeVoxelsAreRejected) {
    auto dir = test::scratchDir();
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), -1.0f, std::numeric_limits<float>::infinity()}) {
        auto grid = openvdb::FloatGrid::create();
        grid->setName("density");
        grid->tree().setValue(openvdb::Coord(0, 0, 0), 1.0f);
        grid->tree().setValue(openvdb::Coord(2, 2, 2), bad);
        const std::string path = (dir / "bad.vdb").string();
        openvdb::io::File(path).write({grid});
        try {
            loadVdb(path);
            FAIL() << "loaded a grid with " << bad;
        } catch (const InvalidArgument& e) {
            EXPECT_NE(std::string(e.what()).find("extinction"), std::string::npos) << e.what();
        }
    }
}

TEST(VdbIo, CorruptAndTruncatedFilesAreIoErrors) {
    auto dir = test::scratchDir();
    test::writeBytes(dir / "junk.vdb", std::string(4096, 'x'));
    EXPECT_THROW(loadVdb((dir / "junk.vdb").string()), IoError);

    saveVdb((dir / "good.vdb").string(), randomVolume({16, 16, 16}, false, 3));
    std::string bytes = test::readBytes(dir / "good.vdb");
    for (int percent = 1; percent < 100; percent += 3) {
        test::writeBytes(dir / "cut.vdb", bytes.substr(0, bytes.size() * size_t(percent) / 100));
        EXPECT_THROW(loadVdb((dir / "cut.vdb").string()), IoError) << "truncated to " << percent << "%";
    }
    // OpenVDB reading past the end used to allocate garbage sizes (15 GB seen): the whole test
    // process must stay far below that.
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    EXPECT_LT(usage.ru_maxrss, 1024L * 1024) << "peak RSS in KiB";
    EXPECT_THROW(loadVdb((dir / "absent.vdb").string()), IoError);
}

TEST(VdbIo, OverTheLimitIsRejectedBeforeAllocating) {
    auto dir = test::scratchDir();
    auto grid = openvdb::FloatGrid::create();
    grid->setName("density");
    grid->tree().setValue(openvdb::Coord(0, 0, 0), 1.0f);
    grid->tree().setValue(openvdb::Coord(4000, 4000, 4000), 1.0f);  // 4001³ box, two voxels
    openvdb::io::File((dir / "huge.vdb").string()).write({grid});
    try {
        loadVdb((dir / "huge.vdb").string());
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("over the limit"), std::string::npos) << e.what();
    }
}

TEST(VdbIo, AnActiveBoxBeyond32BitsIsOverTheLimitNotAnOverflow) {
    // Two voxels at ±2e9: Coord::dim() wraps in 32 bits and once slipped past the 256³ check.
    auto dir = test::scratchDir();
    auto grid = openvdb::FloatGrid::create();
    grid->setName("density");
    grid->tree().setValue(openvdb::Coord(-2000000000, 0, 0), 1.0f);
    grid->tree().setValue(openvdb::Coord(2000000000, 0, 0), 1.0f);
    openvdb::io::File((dir / "far.vdb").string()).write({grid});
    try {
        loadVdb((dir / "far.vdb").string());
        FAIL() << "a 4e9-voxel-wide box loaded";
    } catch (const LimitExceeded& e) {
        EXPECT_NE(std::string(e.what()).find("4000000001x1x1"), std::string::npos) << e.what();
    }
}

TEST(VdbIo, GridsWithAnotherTransformAreResampled) {
    auto dir = test::scratchDir();
    auto density = openvdb::FloatGrid::create();
    density->setName("density");
    density->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
    auto emission = openvdb::Vec3SGrid::create();
    emission->setName("emission");
    emission->setTransform(openvdb::math::Transform::createLinearTransform(1.0));
    for (int k = 0; k < 8; ++k)
        for (int j = 0; j < 8; ++j)
            for (int i = 0; i < 8; ++i) {
                density->tree().setValue(openvdb::Coord(i, j, k), 1.0f);
                emission->tree().setValue(openvdb::Coord(i, j, k), openvdb::Vec3s(float(i), 0, 0));
            }
    openvdb::io::File((dir / "mixed.vdb").string()).write({density, emission});
    Volume v = loadVdb((dir / "mixed.vdb").string());
    // Density voxel (i,j,k) is at world 0.5 i; emission there is its own x index 0.5 i (linear).
    for (int i = 0; i < 8; ++i) EXPECT_NEAR(v.emission()[3 * v.index(i, 2, 2)], 0.5f * float(i), 1e-5f) << i;
}

// Sparse volumes on the host (issue #39): bricks that line up with OpenVDB's leaves, reading without
// densifying (limits counted in active voxels, before anything is allocated), lossless writing.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <sys/resource.h>

#include <cmath>

#include "core/base/errors.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"
#include "test_files.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A soft ball of density (and a Vec3f emission at its core) centred at file index `centre`: leaves
/// and voxels at negative and odd coordinates, so the volume's bricks are offset from its box.
void writeBall(const std::string& path, openvdb::Coord centre, int radius) {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    auto emission = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    emission->setName("emission");
    auto d = density->getAccessor();
    auto e = emission->getAccessor();
    for (int z = -radius; z <= radius; ++z)
        for (int y = -radius; y <= radius; ++y)
            for (int x = -radius; x <= radius; ++x) {
                const double r = std::sqrt(double(x * x + y * y + z * z)) / radius;
                if (r >= 1) continue;
                const openvdb::Coord c = centre + openvdb::Coord(x, y, z);
                d.setValue(c, float(3.0 * (1 - r)));
                if (r < 0.3) e.setValue(c, openvdb::Vec3s(1.5f, 0.5f, float(r)));
            }
    auto xf = openvdb::math::Transform::createLinearTransform(0.05);
    density->setTransform(xf);
    emission->setTransform(xf);
    emission->insertMeta("note", openvdb::StringMetadata("kept"));
    openvdb::io::File(path).write({density, emission});
}

VolumeLimits sparseStorage() {
    VolumeLimits l;
    l.storage = VolumeStorage::Sparse;
    return l;
}

}  // namespace

TEST(SparseVolume, BricksMapEveryVoxelToOnePlaceAndBack) {
    const Int3 dims{19, 8, 13};
    for (Int3 offset : {Int3{0, 0, 0}, Int3{5, 0, 7}}) {
        BrickLayout l = BrickLayout::full(dims, offset);
        EXPECT_EQ(l.brickDims(), (Int3{(19 + offset.x + 7) / 8, 1, (13 + offset.z + 7) / 8}));
        Volume v(l, Mat4());
        std::vector<char> seen(v.storedVoxels(), 0);
        for (int k = 0; k < dims.z; ++k)
            for (int j = 0; j < dims.y; ++j)
                for (int i = 0; i < dims.x; ++i) {
                    const size_t n = v.index(i, j, k);
                    ASSERT_GE(n, size_t(kBrickVoxels));  // never the background brick
                    ASSERT_EQ(seen[n]++, 0);
                    ASSERT_EQ(v.voxelOfStored(n), (Int3{i, j, k}));
                }
        EXPECT_EQ(v.activeVoxels(), size_t(dims.volume()));
    }
}

TEST(SparseVolume, DenseToSparseAndBackIsExact) {
    const Volume dense = makeBuiltinScene("cloud", 30);
    for (Int3 offset : {Int3{0, 0, 0}, Int3{1, 6, 3}}) {
        const Volume sparse = dense.toSparse(offset);
        ASSERT_TRUE(sparse.isSparse());
        EXPECT_LT(sparse.bricks()->activeBricks(), size_t(sparse.bricks()->brickDims().volume()));  // empty corners stay inactive
        sparse.validate();
        const Volume back = sparse.toDense();
        EXPECT_EQ(back.extinction(), dense.extinction());
        EXPECT_EQ(back.albedo(), dense.albedo());
        EXPECT_LT(sparse.memoryBytes(), dense.memoryBytes());
    }
}

TEST(SparseVolume, ReadsLeavesAsBricksWithTheDenseValues) {
    const auto dir = test::scratchDir();
    const std::string path = (dir / "ball.vdb").string();
    writeBall(path, openvdb::Coord(-13, 5, 21), 14);
    const Volume dense = loadVdb(path);
    const Volume sparse = loadVdb(path, sparseStorage());
    ASSERT_FALSE(dense.isSparse());
    ASSERT_TRUE(sparse.isSparse());
    EXPECT_EQ(sparse.dims(), dense.dims());
    EXPECT_EQ(sparse.worldFromIndex(), dense.worldFromIndex());
    // Voxel 0 is file index -26 on x (-13 - 13): 6 into its leaf; 5 - 13 = -8: 0; 21 - 13 = 8: 0.
    EXPECT_EQ(sparse.bricks()->offset(), (Int3{6, 0, 0}));
    // One brick per leaf of the density grid (the emission's leaves lie inside them).
    openvdb::io::File f(path);
    f.open();
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("density"));
    EXPECT_EQ(sparse.bricks()->activeBricks(), grid->tree().leafCount());
    const Volume back = sparse.toDense();
    EXPECT_EQ(back.extinction(), dense.extinction());
    EXPECT_EQ(back.emission(), dense.emission());
}

TEST(SparseVolume, WritesTheFileBackAsItCameAndWhatASolveActivated) {
    const auto dir = test::scratchDir();
    const std::string path = (dir / "ball.vdb").string(), same = (dir / "same.vdb").string(), grown = (dir / "grown.vdb").string();
    writeBall(path, openvdb::Coord(-13, 5, 21), 14);
    Volume v = loadVdb(path, sparseStorage());
    saveVdb(same, v);
    EXPECT_EQ(vdbDifferences(path, same), std::vector<std::string>{});

    // A solve grows emission into a brick that was empty and changes one voxel it had.
    const BrickLayout& bricks = *v.bricks();
    Int3 empty{-1, -1, -1};
    for (int z = 0; z < bricks.brickDims().z && empty.x < 0; ++z)
        for (int x = 0; x < bricks.brickDims().x && empty.x < 0; ++x)
            if (!bricks.isActive({x, 0, z})) empty = {x, 0, z};
    ASSERT_GE(empty.x, 0);
    v.activateBrick(empty);
    const Int3 first = v.bricks()->firstVoxel(empty);
    const Int3 grownVoxel{std::max(first.x, 0) + 1, std::max(first.y, 0) + 1, std::max(first.z, 0) + 1};
    const size_t n = v.index(grownVoxel.x, grownVoxel.y, grownVoxel.z);
    v.emission()[3 * n] = 0.25f;
    const Int3 c{v.dims().x / 2, v.dims().y / 2, v.dims().z / 2};
    v.emission()[3 * v.index(c.x, c.y, c.z) + 2] = 0.125f;
    saveVdb(grown, v);
    const Volume back = loadVdb(grown, sparseStorage());
    EXPECT_EQ(back.emission()[3 * back.index(grownVoxel.x, grownVoxel.y, grownVoxel.z)], 0.25f);
    EXPECT_EQ(back.emission()[3 * back.index(c.x, c.y, c.z) + 2], 0.125f);
    EXPECT_EQ(back.extinction(), v.extinction().size() == back.extinction().size() ? v.extinction() : back.extinction());
    // Only emission's values changed: its name, class, transform and metadata stay, the density is the file's.
    for (const std::string& d : vdbDifferences(path, grown)) EXPECT_NE(d.find("emission"), std::string::npos) << d;
    bool noteKept = false;
    for (const auto& g : inspectVdb(grown))
        for (const auto& [k, val] : g.metadata) noteKept = noteKept || (g.name == "emission" && k == "note" && val == "kept");
    EXPECT_TRUE(noteKept);
}

TEST(SparseVolume, AProductionBoxLoadsInProportionToItsActiveVoxels) {
    // A 2048³ box (two leaves at far corners and a 64³ block between): dense it would be 8.6 G voxels,
    // 97 GiB for one RGB grid. Sparse it holds the leaves.
    const auto dir = test::scratchDir();
    const std::string path = (dir / "wide.vdb").string();
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->tree().setValue(openvdb::Coord(0, 0, 0), 1.0f);
    density->tree().setValue(openvdb::Coord(2047, 2047, 2047), 2.0f);
    for (int z = 0; z < 64; ++z)
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) density->tree().setValue(openvdb::Coord(1000 + x, 900 + y, 1100 + z), 0.5f);
    openvdb::io::File(path).write({density});
    const Volume v = loadVdb(path);  // automatic: over the dense limit, so sparse
    ASSERT_TRUE(v.isSparse());
    EXPECT_EQ(v.dims(), (Int3{2048, 2048, 2048}));
    EXPECT_EQ(v.bricks()->activeBricks(), size_t(2 + 8 * 9 * 9));  // x from 1000 = 125·8 spans 8 leaves, y and z (900, 1100) 9
    EXPECT_LT(v.memoryBytes(), size_t(80) << 20);  // the 256³ table (64 MiB) and 650 bricks (4 MiB)
    EXPECT_EQ(v.extinction()[3 * v.index(2047, 2047, 2047)], 2.0f);
    EXPECT_EQ(v.extinction()[3 * v.index(1030, 930, 1130)], 0.5f);
    EXPECT_EQ(v.extinction()[3 * v.index(500, 500, 500)], 0.0f);
}

TEST(SparseVolume, LimitsCountActiveVoxelsBeforeAllocating) {
    // One active 128³ tile in a 1024³ box: 4096 bricks once read. The count of bricks is checked
    // against the limit before their grids are allocated, and the message says what it counted.
    const auto dir = test::scratchDir();
    const std::string path = (dir / "tile.vdb").string();
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->tree().addTile(2, openvdb::Coord(0, 0, 0), 1.0f, true);  // a 128³ tile (a child of a level-2 node)
    density->insertMeta("volstyle_dense_box_min", openvdb::Vec3IMetadata(openvdb::Vec3i(0, 0, 0)));
    density->insertMeta("volstyle_dense_box_max", openvdb::Vec3IMetadata(openvdb::Vec3i(1023, 1023, 1023)));
    openvdb::io::File(path).write({density});
    VolumeLimits tight;
    tight.maxActiveVoxels = 1 << 20;
    try {
        loadVdb(path, tight);
        FAIL() << "loaded over the limit";
    } catch (const LimitExceeded& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("4096 active bricks"), std::string::npos) << m;  // 128³ / 8³
        EXPECT_NE(m.find("1048576 active voxels"), std::string::npos) << m;
    }
    const Volume v = loadVdb(path);  // 2 M voxels: within the default
    EXPECT_EQ(v.bricks()->activeBricks(), size_t(4096));
    EXPECT_EQ(v.bricks()->slots(), size_t(2));  // the background and the tile's one shared brick
    EXPECT_EQ(v.extinction()[3 * v.index(127, 127, 127)], 1.0f);
    EXPECT_EQ(v.extinction()[3 * v.index(128, 0, 0)], 0.0f);
    EXPECT_EQ(v.activeVoxels(), size_t(128 * 128 * 128));
}

TEST(SparseVolume, TilesStayTilesWhenReadAndWritten) {
    // A 128³ tile of density 2 beside a ball of leaves: the tile's 4096 bricks share one stored
    // brick, read the tile's value, and a solve-style edit elsewhere writes the tile back as a tile.
    const auto dir = test::scratchDir();
    const std::string path = (dir / "tiled.vdb").string(), same = (dir / "same.vdb").string(), edited = (dir / "edited.vdb").string();
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->tree().addTile(2, openvdb::Coord(128, 0, 0), 2.0f, true);
    for (int z = 0; z < 20; ++z)
        for (int y = 0; y < 20; ++y)
            for (int x = 0; x < 20; ++x) density->tree().setValue(openvdb::Coord(40 + x, 50 + y, 60 + z), 0.5f + 0.01f * float(x));
    openvdb::io::File(path).write({density});
    Volume v = loadVdb(path, sparseStorage());
    ASSERT_TRUE(v.isSparse());
    const BrickLayout& b = *v.bricks();
    const size_t leafBricks = 3 * 3 * 3;  // 20 voxels from 40, 50 and 60 span 3 leaves on each axis
    EXPECT_EQ(b.activeBricks(), 4096 + leafBricks);
    EXPECT_EQ(b.slots(), 1 + leafBricks + 1);
    EXPECT_TRUE(b.hasSharedSlots());
    // The box starts at file index (40, 0, 0): the ball's low x, the tile's low y and z.
    EXPECT_EQ(v.dims(), (Int3{216, 128, 128}));
    EXPECT_EQ(v.extinction()[3 * v.index(128 + 77 - 40, 5, 100)], 2.0f);
    EXPECT_EQ(v.activeVoxels(), size_t(4096 + leafBricks) * kBrickVoxels);
    // The dense copy agrees voxel for voxel.
    const Volume dense = loadVdb(path);
    EXPECT_EQ(v.toDense().extinction(), dense.extinction());
    saveVdb(same, v);
    EXPECT_EQ(vdbDifferences(path, same), std::vector<std::string>{});
    // An edit in the ball: the tile is written back as it was (one tile, no leaves under it).
    for (int c = 0; c < 3; ++c) v.extinction()[3 * v.index(45 - 40, 55, 65) + size_t(c)] = 0.75f;  // grey: stays a float grid
    saveVdb(edited, v);
    openvdb::io::File f(edited);
    f.open();
    auto back = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("density"));
    ASSERT_TRUE(back);
    EXPECT_EQ(back->tree().leafCount(), density->tree().leafCount());
    EXPECT_EQ(back->tree().getValue(openvdb::Coord(200, 100, 100)), 2.0f);
    // Giving every tile brick its own slot (as a solve does) keeps every value.
    Volume unshared = v;
    unshared.unshareTiles();
    EXPECT_FALSE(unshared.bricks()->hasSharedSlots());
    EXPECT_EQ(unshared.toDense().extinction(), v.toDense().extinction());
}

// Occluder meshes (SPEC §7): OBJ, PLY and glTF through assimp, flattened to one triangle mesh,
// and the errors a bad file gets.
#include <gtest/gtest.h>

#include <cmath>

#include "core/base/errors.h"
#include "core/stylize/mesh_io.h"
#include "core/stylize/scene.h"
#include "test_files.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

// A unit square in the xz-plane at y = 1 (two triangles), in each format.
const char* kObj = "v 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nf 1 4 3 2\n";
const char* kPly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 1 0\n1 1 0\n1 1 1\n0 1 1\n4 0 3 2 1\n";
// glTF 2.0 with an embedded buffer: 4 float3 positions (48 bytes) then 6 uint16 indices (12 bytes).
std::string gltf() {
    return R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"scene":0,
      "nodes":[{"mesh":0,"translation":[0,0.5,0]}],
      "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
      "buffers":[{"byteLength":60,"uri":"data:application/octet-stream;base64,AAAAAAAAAD8AAAAAAACAPwAAAD8AAAAAAACAPwAAAD8AAIA/AAAAAAAAAD8AAIA/AAADAAIAAAACAAEA"}],
      "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0.5,0],"max":[1,0.5,1]},
                   {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}]})";
}

void expectUnitSquareAtHeightOne(const Mesh& m) {
    ASSERT_EQ(m.triangleCount(), 2u);
    auto [lo, hi] = m.bounds();
    EXPECT_NEAR(lo.x, 0, 1e-6);
    EXPECT_NEAR(hi.x, 1, 1e-6);
    EXPECT_NEAR(lo.z, 0, 1e-6);
    EXPECT_NEAR(hi.z, 1, 1e-6);
    EXPECT_NEAR(lo.y, 1, 1e-6);
    EXPECT_NEAR(hi.y, 1, 1e-6);
    for (const Vec3& n : m.normals) {
        EXPECT_NEAR(std::abs(n.y), 1, 1e-5);  // generated smooth normals of a flat square
        EXPECT_NEAR(length(n), 1, 1e-5);
    }
}

}  // namespace

TEST(MeshIo, ObjPlyAndGltfGiveTheSameSquare) {
    const auto dir = test::scratchDir();
    test::writeBytes(dir / "square.obj", kObj);
    test::writeBytes(dir / "square.ply", kPly);
    test::writeBytes(dir / "square.gltf", gltf());  // node translation 0.5 + positions at y 0.5
    for (const char* name : {"square.obj", "square.ply", "square.gltf"}) {
        SCOPED_TRACE(name);
        expectUnitSquareAtHeightOne(loadMesh((dir / name).string()));
    }
    expectUnitSquareAtHeightOne(loadMeshFromMemory(kObj, "obj"));
    expectUnitSquareAtHeightOne(loadMeshFromMemory(kPly, "ply"));
    expectUnitSquareAtHeightOne(loadMeshFromMemory(gltf(), "gltf"));
}

TEST(MeshIo, BadFilesSayWhatIsWrong) {
    const auto dir = test::scratchDir();
    auto message = [](auto&& f) {
        try {
            f();
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("(no error)");
    };
    EXPECT_NE(message([&] { loadMesh((dir / "missing.obj").string()); }).find("no such file"), std::string::npos);
    test::writeBytes(dir / "empty.obj", "");
    EXPECT_NE(message([&] { loadMesh((dir / "empty.obj").string()); }).find("is empty"), std::string::npos);
    test::writeBytes(dir / "points.obj", "v 0 0 0\nv 1 0 0\np 1\np 2\n");
    EXPECT_NE(message([&] { loadMesh((dir / "points.obj").string()); }).find("mesh"), std::string::npos);
    test::writeBytes(dir / "garbage.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 99999999\nend_header\nxx");
    EXPECT_THROW(loadMesh((dir / "garbage.ply").string()), Error);
    EXPECT_THROW(loadMeshFromMemory("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "obj"), InvalidArgument);
    EXPECT_NE(message([] { loadMeshFromMemory(kObj, "fbx"); }).find("not one of obj, ply, gltf, glb"), std::string::npos);
    MeshLimits small;
    small.maxVertices = 3;
    EXPECT_THROW(loadMeshFromMemory(kObj, "obj", small), LimitExceeded);
    small = {};
    small.maxFileBytes = 10;
    EXPECT_THROW(loadMeshFromMemory(kObj, "obj", small), LimitExceeded);
}

TEST(MeshIo, HostileFilesAreRefusedBeforeTheyCostMemory) {
    // Found by review: a 32 KB glTF whose nodes reuse each other 4 times over 8 levels (assimp's
    // pre-transform expanded every instance: 8.6 GB), a 177-byte PLY whose header claims 10^8
    // vertices (1.3 GB allocated from the claim), an STL (a format volstyle does not document).
    const std::string dir = std::string(VOLSTYLE_SOURCE_DIR) + "/tests/data/meshes/";
    EXPECT_THROW(loadMesh(dir + "instanced-dag.gltf"), LimitExceeded);
    EXPECT_THROW(loadMesh(dir + "claims-1e8-vertices.ply"), LimitExceeded);
    EXPECT_THROW(loadMeshFromMemory(test::readBytes(dir + "claims-1e8-vertices.ply"), "ply"), LimitExceeded);
    const auto scratch = test::scratchDir();
    test::writeBytes(scratch / "tri.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n");
    EXPECT_THROW(loadMesh((scratch / "tri.stl").string()), InvalidArgument);
    EXPECT_THROW(loadMeshFromMemory("v 1e38 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "obj"), InvalidArgument);  // Inf once transformed
}

TEST(MeshIo, AnUploadedGltfCannotReadTheServersFiles) {
    // Review of issue #11: a glTF upload whose buffer URI named a file on the server was read
    // from disk (its bytes came back as the mesh's bounds). From memory only data: URIs resolve;
    // a file's own glTF may still use the buffers beside it.
    const auto dir = test::scratchDir();
    const float triangle[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    test::writeBytes(dir / "secret.bin", std::string(reinterpret_cast<const char*>(triangle), sizeof triangle));
    auto gltf = [](const std::string& uri) {
        return R"({"asset":{"version":"2.0"},"buffers":[{"uri":")" + uri + R"(","byteLength":36}],)"
               R"("bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,)"
               R"("type":"VEC3","min":[0,0,0],"max":[1,1,0]}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
               R"("nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0})";
    };
    test::writeBytes(dir / "beside.gltf", gltf("secret.bin"));
    EXPECT_EQ(loadMesh((dir / "beside.gltf").string()).triangleCount(), 1u) << "a file's neighbouring buffer is fine";
    EXPECT_ANY_THROW(loadMeshFromMemory(gltf((dir / "secret.bin").string()), "gltf")) << "an absolute path";
    EXPECT_ANY_THROW(loadMeshFromMemory(gltf("secret.bin"), "gltf")) << "a relative one";
    EXPECT_ANY_THROW(loadMeshFromMemory(gltf("file://" + (dir / "secret.bin").string()), "gltf"));
}

TEST(StylizerScene, TheBuiltinForestIsValidAndLetsLightThrough) {
    const StylizerScene forest = builtinForest();
    EXPECT_NO_THROW(forest.validate());
    ASSERT_EQ(forest.occluders.size(), 2u);
    EXPECT_GT(forest.occluders[1].mesh->triangleCount(), 10000u);  // leaves: foliage, not a solid roof
    StylizerScene bad = forest;
    bad.light.shadowMapSize = 100;
    EXPECT_THROW(bad.validate(), InvalidArgument);
    bad = forest;
    Mesh broken = *bad.occluders[0].mesh;
    broken.positions[0].x = std::nanf("");
    bad.occluders[0].mesh = std::make_shared<const Mesh>(std::move(broken));
    EXPECT_THROW(bad.validate(), InvalidArgument);
    bad = forest;
    bad.medium.extinction = 1e308;  // would be Inf as a float
    EXPECT_THROW(bad.validate(), InvalidArgument);
    bad = forest;
    bad.light.irradiance = {1e38, 1, 1};
    EXPECT_THROW(bad.validate(), InvalidArgument);
}

// Uploaded meshes (issue #35): a glTF's structure is checked before any mesh library reads it
// (protocol/mesh_upload_check.h), PLY headers are held to their bytes whatever the line endings,
// and the server parses uploads only in its child reader (server/runtime/mesh_reader.h).
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "core/base/errors.h"
#include "core/stylize/mesh_io.h"
#include "protocol/mesh_upload_check.h"
#include "server/runtime/mesh_reader.h"
#include "test_files.h"

using namespace volstyle;

namespace {

const std::string kTriangleBase64 = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";  // 9 floats: a unit right triangle

/// A glTF (JSON) whose nodes are `nodes` (a JSON array text) over one embedded triangle.
std::string gltf(const std::string& nodes, const std::string& extra = "") {
    return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":)" + nodes +
           R"(,"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
           R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],)"
           R"("bufferViews":[{"buffer":0,"byteLength":36}],)"
           R"("buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,)" + kTriangleBase64 + "\"}]" + extra + "}";
}

std::string chain(int depth) {
    std::string nodes = "[";
    for (int i = 0; i + 1 < depth; ++i) nodes += "{\"children\":[" + std::to_string(i + 1) + "]},";
    return nodes + "{\"mesh\":0}]";
}

std::string doubling(int levels) {
    std::string nodes = "[";
    for (int i = 0; i < levels; ++i) nodes += "{\"children\":[" + std::to_string(i + 1) + "," + std::to_string(i + 1) + "]},";
    return nodes + "{\"mesh\":0}]";
}

/// A GLB around `json` and a 36-byte BIN chunk; `length` overrides the header's total.
std::string glb(std::string json, long length = -1) {
    while (json.size() % 4) json += ' ';
    const auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
    std::string bin(36, '\0');
    const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::memcpy(bin.data(), tri, 36);
    const std::string chunks = u32(uint32_t(json.size())) + u32(0x4E4F534A) + json + u32(36) + u32(0x004E4942) + bin;
    return "glTF" + u32(2) + u32(length >= 0 ? uint32_t(length) : uint32_t(12 + chunks.size())) + chunks;
}

std::string glbJson(const std::string& buffers, const std::string& extra = "") {
    std::string j = gltf("[{\"mesh\":0}]", extra);
    const size_t at = j.find("\"buffers\":");
    return j.substr(0, at) + "\"buffers\":" + buffers + j.substr(j.find(']', at) + 1);
}

template <typename E>
std::string refusal(const std::string& bytes, const std::string& format) {
    try {
        protocol::checkMeshUpload(bytes, format, core::MeshLimits{});
    } catch (const E& e) {
        return e.what();
    } catch (const std::exception& e) {
        return std::string("wrong kind: ") + e.what();
    }
    return "accepted";
}

std::string hostileFile(const std::string& name) {
    return test::readBytes(std::string(VOLSTYLE_SOURCE_DIR) + "/tests/data/hostile/" + name);
}

/// What the server's child reader (this build's binary) refuses `bytes` with, as an `E`.
template <typename E>
std::string childRefusal(const std::string& bytes, const std::string& format) {
    server::VdbReaderOptions reader;
    reader.executable = VOLSTYLE_BINARY;
    try {
        server::loadUntrustedMesh(bytes, format, {}, reader);
    } catch (const E& e) {
        return e.what();
    } catch (const std::exception& e) {
        return std::string("wrong kind: ") + e.what();
    }
    return "accepted";
}

}  // namespace

TEST(MeshUploadCheck, AGoodGltfAndGlbPassAndRead) {
    EXPECT_NO_THROW(protocol::checkMeshUpload(gltf(chain(64)), "gltf", {}));  // 64 levels: the limit
    EXPECT_NO_THROW(protocol::checkMeshUpload(glb(glbJson(R"([{"byteLength":36}])")), "glb", {}));
    EXPECT_EQ(core::loadMeshFromMemory(gltf(chain(64)), "gltf").triangleCount(), 1u);
    EXPECT_EQ(core::loadMeshFromMemory(glb(glbJson(R"([{"byteLength":36}])")), "glb").triangleCount(), 1u);
}

TEST(MeshUploadCheck, NestingCyclesAndExpansionAreCountedWithoutExpanding) {
    // 20,000 nested nodes overflowed assimp's stack inside the server.
    for (int depth : {65, 20000})
        EXPECT_NE(refusal<LimitExceeded>(gltf(chain(depth)), "gltf").find("nest"), std::string::npos) << depth;
    // Each node referencing the next twice: 2^24 copies (10.75 GB inside assimp), counted exactly.
    EXPECT_NE(refusal<LimitExceeded>(gltf(doubling(24)), "gltf").find("into 33554431 node copies"), std::string::npos);
    EXPECT_NE(refusal<LimitExceeded>(gltf(doubling(60)), "gltf").find("over 10^15"), std::string::npos) << "no overflow";
    EXPECT_EQ(refusal<LimitExceeded>(gltf(doubling(10)), "gltf"), "accepted") << "2047 copies are fine";
    EXPECT_NE(refusal<InvalidArgument>(gltf(R"([{"children":[1]},{"children":[0],"mesh":0}])"), "gltf").find("cycle"),
              std::string::npos);
    EXPECT_NE(refusal<InvalidArgument>(gltf(R"([{"children":[7]}])"), "gltf").find("not a node index"), std::string::npos);
    std::string deep = gltf("[{\"mesh\":0}]");
    deep.insert(deep.size() - 1, ",\"extras\":" + std::string(100000, '[') + std::string(100000, ']'));
    EXPECT_NE(refusal<InvalidArgument>(deep, "gltf").find("JSON nests over 64"), std::string::npos);
}

TEST(MeshUploadCheck, InstancedVerticesAreCountedAgainstTheLimit) {
    core::MeshLimits limits;
    limits.maxVertices = 3 * 1000;
    // 2^10 = 1024 instances of a 3-vertex triangle: 3,072 vertices once expanded.
    try {
        protocol::checkMeshUpload(gltf(doubling(10)), "gltf", limits);
        FAIL() << "accepted 3072 instanced vertices over a limit of 3000";
    } catch (const LimitExceeded& e) {
        EXPECT_NE(std::string(e.what()).find("3072 vertices"), std::string::npos) << e.what();
    }
}

TEST(MeshUploadCheck, GlbLengthsAndBuffersMustAddUp) {
    const std::string good = glbJson(R"([{"byteLength":36}])");
    EXPECT_NE(refusal<InvalidArgument>(glb(good, 0xFFFFFFFFL), "glb").find("declares 4294967295 bytes"), std::string::npos);
    EXPECT_NE(refusal<InvalidArgument>(glb(good).substr(0, 40), "glb").find("declares"), std::string::npos) << "truncated";
    EXPECT_NE(refusal<InvalidArgument>(glb(glbJson(R"([{"byteLength":1099511627776}])")), "glb").find("outside 0..4294967295"),
              std::string::npos);
    EXPECT_NE(refusal<InvalidArgument>(glb(glbJson(R"([{"byteLength":4096}])")), "glb").find("BIN chunk holds 36"), std::string::npos);
    EXPECT_NE(refusal<InvalidArgument>(glb(glbJson(R"([{"byteLength":36,"uri":"/etc/passwd"}])")), "glb").find("refers to the file"),
              std::string::npos);
    EXPECT_NE(refusal<InvalidArgument>(gltf("[{\"mesh\":0}]").replace(gltf("[{\"mesh\":0}]").find("\"count\":3"), 9, "\"count\":30"), "gltf")
                  .find("reads 360 bytes of a buffer view of 36"),
              std::string::npos);
}

TEST(MeshUploadCheck, RequiredExtensionsAreHonouredOrRefusedByName) {
    const std::string draco = R"(,"extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"])";
    EXPECT_NE(refusal<InvalidArgument>(gltf("[{\"mesh\":0}]", draco), "gltf").find("KHR_draco_mesh_compression"), std::string::npos);
    EXPECT_EQ(refusal<InvalidArgument>(gltf("[{\"mesh\":0}]", R"(,"extensionsRequired":["KHR_materials_unlit"])"), "gltf"), "accepted");
}

TEST(MeshUploadCheck, PlyHeadersAreHeldToTheirBytesWhateverTheLineEndings) {
    const auto ply = [](const std::string& count, const std::string& nl) {
        return "ply" + nl + "format ascii 1.0" + nl + "element vertex " + count + nl + "property float x" + nl + "property float y" + nl +
               "property float z" + nl + "element face 1" + nl + "property list uchar int vertex_indices" + nl + "end_header" + nl +
               "0 0 0" + nl + "1 0 0" + nl + "0 1 0" + nl + "3 0 1 2" + nl;
    };
    for (const std::string nl : {"\n", "\r\n", "\r"}) {
        EXPECT_EQ(core::loadMeshFromMemory(ply("3", nl), "ply").triangleCount(), 1u) << "one ending throughout is fine";
        EXPECT_THROW(core::loadMeshFromMemory(ply("3000000", nl), "ply"), InvalidArgument) << "a 3M-vertex claim in ~200 bytes";
        EXPECT_THROW(core::loadMeshFromMemory(ply("1000000000", nl), "ply"), LimitExceeded);
        EXPECT_THROW(core::loadMeshFromMemory(ply("18446744074709551616", nl), "ply"), LimitExceeded) << "2^64 + 10^9: not wrapped";
        EXPECT_THROW(core::loadMeshFromMemory(ply("-5", nl), "ply"), InvalidArgument);
    }
    // Found by fuzz_mesh_ply: headers on which assimp's parser never returns.
    std::string mixed = ply("3", "\n");
    mixed.replace(mixed.find("\nend_header"), 1, "\r");
    EXPECT_THROW(core::loadMeshFromMemory(mixed, "ply"), InvalidArgument) << "mixed line endings";
    std::string version = ply("3", "\n");
    version.replace(version.find("1.0"), 3, "5.0");
    EXPECT_THROW(core::loadMeshFromMemory(version, "ply"), InvalidArgument) << "format version 5.0";
    EXPECT_THROW(core::loadMeshFromMemory("ply\n\vend_header\n", "ply"), InvalidArgument) << "end_header behind a vertical tab";
}

TEST(MeshReader, UploadsAreParsedInTheChildAndComeBackWhole) {
    server::VdbReaderOptions reader;
    reader.executable = VOLSTYLE_BINARY;
    const core::Mesh inProcess = core::loadMeshFromMemory(gltf(chain(3)), "gltf");
    const core::Mesh child = server::loadUntrustedMesh(gltf(chain(3)), "gltf", {}, reader);
    EXPECT_EQ(child.positions.size(), inProcess.positions.size());
    EXPECT_EQ(child.indices, inProcess.indices);
    for (size_t i = 0; i < child.positions.size(); ++i) EXPECT_EQ(child.positions[i], inProcess.positions[i]) << i;
    // The child's refusals keep their kind: 413 for limits, 422 for damage.
    EXPECT_THROW(server::loadUntrustedMesh(gltf(doubling(24)), "gltf", {}, reader), LimitExceeded);
    EXPECT_THROW(server::loadUntrustedMesh("v 0 0 0\nv 1 0 0\n", "obj", {}, reader), InvalidArgument);
}

TEST(MeshReader, APlyThatAbortedAssimpIsRefusedByItsHeader) {
    // Found by fuzz_mesh_ply: a binary PLY whose header breaks off mid-line ("...yrp\noperty float
    // z") tripped an ai_assert inside assimp 5.2.5's triangulation (Debian builds it with asserts:
    // abort()); in the server's process that upload ended the server. The header grammar now
    // refuses it before assimp sees it (and the child reader would contain the abort).
    const std::string bytes = hostileFile("assimp-ply-abort.ply");
    ASSERT_EQ(bytes.size(), 218u);
    EXPECT_NE(childRefusal<InvalidArgument>(bytes, "ply").find("PLY header line 6 ('operty float z')"), std::string::npos);
}

TEST(MeshReader, APlyBodyThatAbortsAssimpIsARefusedUploadNotADeadServer) {
    // Found by fuzz_mesh_ply after the header grammar: a well-formed ASCII header over a body with
    // a NUL and a quote in it trips the same ai_assert (abort) in assimp's triangulation. Only the
    // child reader can contain this one.
    const std::string bytes = hostileFile("assimp-ply-body-abort.ply");
    ASSERT_EQ(bytes.size(), 180u);
    EXPECT_NO_THROW(protocol::checkMeshUpload(bytes, "ply", {}));
    EXPECT_NE(childRefusal<IoError>(bytes, "ply").find("crashed the mesh reader (signal 6, inside assimp)"), std::string::npos);
}

TEST(MeshReader, AReaderThatCrashesIsARefusedUploadNotACrash) {
    const std::string script = (std::filesystem::temp_directory_path() / "volstyle-fake-mesh-reader").string();
    std::ofstream(script) << "#!/bin/sh\nkill -ABRT $$\n";
    std::filesystem::permissions(script, std::filesystem::perms::owner_all);
    server::VdbReaderOptions reader;
    reader.executable = script;
    try {
        server::loadUntrustedMesh(gltf("[{\"mesh\":0}]"), "gltf", {}, reader);
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("crashed the mesh reader (signal 6, inside assimp)"), std::string::npos) << e.what();
    }
}

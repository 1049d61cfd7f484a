// bench/sparse_sampling (issue #39): which sparse structure the volume should live in on the GPU,
// measured on this machine's renderer. A synthetic sparse field (smoke-like blobs, OpenVDB) at
// 1%, 5% and 20% activity in N³ boxes is marched by the same kernel
// (bench/shaders/sparse_sampling.comp: one ray per pixel along +z, half-voxel steps, trilinear)
// stored three ways: dense R32F (today's layout; up to 256³), 8³ bricks in an atlas with an
// indirection texture (a table lookup per corner, or one a cell when its corners share a brick),
// and NanoVDB through PNanoVDB. Prints memory, ms (wall clock of a finished dispatch) and the largest
// difference from the first method per row (bricks must be 0: the same 8 values, the same
// weights). Usage: sparse_sampling_bench [--quick]
#include <openvdb/openvdb.h>
#include <nanovdb/util/OpenToNanoVDB.h>

#include <epoxy/gl.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/gpu/gpu_device.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

/// A field of soft blobs filling `fraction` of the N³ box (value 1 − r/R inside each).
openvdb::FloatGrid::Ptr sparseField(int n, double fraction, unsigned seed) {
    auto grid = openvdb::FloatGrid::create(0.0f);
    auto acc = grid->getAccessor();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    const double target = fraction * double(n) * n * n;
    while (double(grid->activeVoxelCount()) < target) {
        const double r = n * (0.02 + 0.05 * u(rng));
        const double cx = r + (n - 2 * r) * u(rng), cy = r + (n - 2 * r) * u(rng), cz = r + (n - 2 * r) * u(rng);
        for (int z = int(cz - r); z <= int(cz + r); ++z)
            for (int y = int(cy - r); y <= int(cy + r); ++y)
                for (int x = int(cx - r); x <= int(cx + r); ++x) {
                    const double d = std::sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz));
                    if (d < r && x >= 0 && y >= 0 && z >= 0 && x < n && y < n && z < n)
                        acc.setValue({x, y, z}, std::max(acc.getValue({x, y, z}), float(0.2 * (1 - d / r))));
                }
    }
    return grid;
}

struct Stored {
    std::vector<gl::Texture> textures;
    gl::Buffer buffer;
    size_t bytes = 0;
    int atlasBricks[3] = {1, 1, 1};
};

gl::Texture texture3D(GLenum format, int w, int h, int d, GLenum type, const void* data, const char* label) {
    gl::Texture t = gl::createTexture(GL_TEXTURE_3D, label);
    glTextureStorage3D(t.id(), 1, format, w, h, d);
    glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage3D(t.id(), 0, 0, 0, 0, w, h, d, format == GL_R32UI ? GL_RED_INTEGER : GL_RED, type, data);
    return t;
}

Stored dense(const openvdb::FloatGrid& grid, int n) {
    std::vector<float> v(size_t(n) * n * n, 0.0f);
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const auto c = it.getCoord();
        v[(size_t(c.z()) * n + c.y()) * n + c.x()] = *it;
    }
    Stored s;
    s.textures.push_back(texture3D(GL_R32F, n, n, n, GL_FLOAT, v.data(), "dense"));
    s.bytes = v.size() * 4;
    return s;
}

Stored bricks(const openvdb::FloatGrid& grid, int n) {
    std::vector<const openvdb::FloatTree::LeafNodeType*> leaves;
    for (auto it = grid.tree().cbeginLeaf(); it; ++it) leaves.push_back(it.getLeaf());
    Stored s;
    const int count = int(leaves.size()), side = std::max(1, int(std::ceil(std::cbrt(double(count)))));
    s.atlasBricks[0] = s.atlasBricks[1] = side;
    s.atlasBricks[2] = (count + side * side - 1) / (side * side);
    const int aw = 8 * side, ah = 8 * side, ad = 8 * s.atlasBricks[2], nb = n / 8;
    std::vector<float> atlas(size_t(aw) * ah * ad, 0.0f);
    std::vector<uint32_t> table(size_t(nb) * nb * nb, 0);
    for (int b = 0; b < count; ++b) {
        const auto origin = leaves[b]->origin();
        table[(size_t(origin.z() / 8) * nb + origin.y() / 8) * nb + origin.x() / 8] = uint32_t(b + 1);
        const int bx = b % side, by = (b / side) % side, bz = b / (side * side);
        for (int z = 0; z < 8; ++z)
            for (int y = 0; y < 8; ++y)
                for (int x = 0; x < 8; ++x)
                    atlas[(size_t(bz * 8 + z) * ah + by * 8 + y) * aw + bx * 8 + x] = leaves[b]->getValue(openvdb::Coord(x, y, z) + origin);
    }
    s.textures.push_back(texture3D(GL_R32F, aw, ah, ad, GL_FLOAT, atlas.data(), "brick atlas"));
    s.textures.push_back(texture3D(GL_R32UI, nb, nb, nb, GL_UNSIGNED_INT, table.data(), "brick table"));
    s.bytes = atlas.size() * 4 + table.size() * 4;
    return s;
}

Stored nano(const openvdb::FloatGrid& grid) {
    auto handle = nanovdb::openToNanoVDB(grid);
    Stored s;
    s.bytes = handle.size();
    s.buffer = gl::createBuffer(handle.size(), handle.data(), 0, "nanovdb grid");
    return s;
}

/// PNanoVDB from Debian's headers, bench/shaders from the source tree, the rest embedded.
std::string loadBenchShader(const std::string& name) {
    const std::string path = name.rfind("nanovdb/", 0) == 0 ? "/usr/include/" + name : std::string(VOLSTYLE_SOURCE_DIR) + "/bench/shaders/" + name;
    std::ifstream f(path);
    if (!f) return gl::loadShaderSource(name);
    std::ostringstream text;
    text << f.rdbuf();
    return text.str();
}

/// Marches the rays through `stored` with `method`; returns (best GPU ms of 3, the depths).
std::pair<double, std::vector<float>> march(GpuDevice& device, const Stored& stored, int method, int n, int size) {
    const gl::Program& program = device.program(gl::ShaderBuilder("sparse_sampling.comp").define("METHOD", method).loader(loadBenchShader));
    gl::Buffer out = gl::createBuffer(size_t(size) * size * 4, nullptr, GL_MAP_READ_BIT, "depths");
    glUseProgram(program.id());
    glProgramUniform1i(program.id(), glGetUniformLocation(program.id(), "uSize"), size);
    glProgramUniform1i(program.id(), glGetUniformLocation(program.id(), "uN"), n);
    glProgramUniform3i(program.id(), glGetUniformLocation(program.id(), "uAtlasBricks"), stored.atlasBricks[0], stored.atlasBricks[1],
                       stored.atlasBricks[2]);
    for (size_t k = 0; k < stored.textures.size(); ++k) glBindTextureUnit(GLuint(k), stored.textures[k].id());
    if (stored.buffer) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, stored.buffer.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, out.id());
    double best = 1e30;  // wall clock around a finished dispatch: llvmpipe's timer queries read 0
    glFinish();
    for (int k = 0; k < 3; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        glDispatchCompute(GLuint((size + 7) / 8), GLuint((size + 7) / 8), 1);
        glFinish();
        best = std::min(best, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<float> depths(size_t(size) * size);
    glGetNamedBufferSubData(out.id(), 0, GLsizeiptr(depths.size() * 4), depths.data());
    return {best, depths};
}

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && !std::strcmp(argv[1], "--quick");
    openvdb::initialize();
    auto device = GpuDevice::create();
    const int size = quick ? 64 : 256;
    std::printf("sparse sampling on %s: %d² rays along +z, half-voxel steps, trilinear (8 fetches a sample)\n\n",
                device->capabilities().renderer.c_str(), size);
    std::printf("| box | active | method | GPU memory | ms | max |difference| | mean depth |\n|---|---|---|---|---|---|---|\n");
    const std::vector<int> boxes = quick ? std::vector<int>{64} : std::vector<int>{128, 256, 512};
    std::vector<std::string> json;
    for (int n : boxes)
        for (double fraction : {0.01, 0.05, 0.20}) {
            auto grid = sparseField(n, fraction, 7u + unsigned(n));
            const double active = double(grid->activeVoxelCount()) / (double(n) * n * n);
            std::vector<float> reference;
            const char* names[] = {"dense", "bricks 8³", "NanoVDB", "bricks 8³, a lookup a cell"};
            for (int method = 0; method < 4; ++method) {
                if (method == 0 && n > 256) continue;  // 512³ dense: 512 MiB of one channel
                const Stored stored = method == 0 ? dense(*grid, n) : method == 2 ? nano(*grid) : bricks(*grid, n);
                auto [ms, depths] = march(*device, stored, method, n, size);
                double worst = 0;
                if (reference.empty()) reference = depths;
                for (size_t i = 0; i < depths.size(); ++i) worst = std::max(worst, double(std::abs(depths[i] - reference[i])));
                double mean = 0;
                for (float d : depths) mean += d / double(depths.size());
                std::printf("| %d³ | %.1f%% | %s | %.1f MiB | %.1f | %.3g | %.4g |\n", n, 100 * active, names[method], stored.bytes / 1048576.0, ms,
                            worst, mean);
                std::ostringstream j;
                j << R"({"bench":"sparse_sampling","box":)" << n << R"(,"active":)" << active << R"(,"method":")" << names[method]
                  << R"(","bytes":)" << stored.bytes << R"(,"ms":)" << ms << R"(,"max_difference":)" << worst << "}";
                json.push_back(j.str());
            }
        }
    std::printf("\n");
    for (const auto& line : json) std::printf("%s\n", line.c_str());
    return 0;
}

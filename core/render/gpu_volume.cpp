#include "core/render/gpu_volume.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <string_view>

#include "core/base/errors.h"
#include "core/render/curved_paths.h"
#include "core/gl/object.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

static_assert(kBrickSide == layout::kBrickSize, "the host's bricks are the GPU's");

namespace {

std::atomic<uint64_t> g_nextVersion{1};

size_t tableHash(const BrickLayout& bricks) {
    const auto& t = bricks.slotTable();
    return std::hash<std::string_view>()(std::string_view(reinterpret_cast<const char*>(t.data()), t.size() * sizeof(uint32_t)));
}

gl::Texture uploadRgb(const std::vector<float>& rgb, Int3 dims, const char* label) {
    gl::Texture tex = gl::createTexture(GL_TEXTURE_3D, label);
    glTextureStorage3D(tex.id(), 1, GL_RGB32F, dims.x, dims.y, dims.z);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage3D(tex.id(), 0, 0, 0, 0, dims.x, dims.y, dims.z, GL_RGB, GL_FLOAT, rgb.data());
    // Clamp-to-edge linear sampling for the hardware-filter variant (texelFetch ignores it).
    glTextureParameteri(tex.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(tex.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
        glTextureParameteri(tex.id(), wrap, GL_CLAMP_TO_EDGE);
    return tex;
}

/// The atlas of a sparse volume: slot s at atlas brick (s mod ax, s / ax mod ay, s / (ax ay)).
struct Atlas {
    Int3 bricks;
    Int3 brickOf(size_t slot) const {
        return {int(slot % size_t(bricks.x)), int(slot / size_t(bricks.x) % size_t(bricks.y)), int(slot / (size_t(bricks.x) * size_t(bricks.y)))};
    }
    static Atlas forSlots(size_t slots, int maxTexels) {
        const int maxBricks = std::min(maxTexels / kBrickSide, 1 << layout::kAtlasBits);
        const int side = std::min(maxBricks, int(std::ceil(std::cbrt(double(slots)))));
        const int rows = int(std::min<size_t>(size_t(maxBricks), (slots + size_t(side) - 1) / size_t(side)));
        const size_t layers = (slots + size_t(side) * size_t(rows) - 1) / (size_t(side) * size_t(rows));
        if (layers > size_t(maxBricks))
            throw GpuError("GpuVolume: " + std::to_string(slots) + " bricks do not fit an atlas within this GPU's 3D texture limit of " +
                           std::to_string(maxTexels));
        return {{side, rows, int(layers)}};
    }
};

/// An RGB32F atlas of a sparse grid (bricks in slot order, 3 floats a voxel), uploaded a layer of
/// atlas bricks at a time.
gl::Texture uploadAtlas(const std::vector<float>& rgb, const Atlas& atlas, size_t slots, const char* label) {
    const Int3 texels{atlas.bricks.x * kBrickSide, atlas.bricks.y * kBrickSide, atlas.bricks.z * kBrickSide};
    gl::Texture tex = gl::createTexture(GL_TEXTURE_3D, label);
    glTextureStorage3D(tex.id(), 1, GL_RGB32F, texels.x, texels.y, texels.z);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    const size_t perLayer = size_t(atlas.bricks.x) * size_t(atlas.bricks.y);
    std::vector<float> layer(size_t(texels.x) * size_t(texels.y) * kBrickSide * 3, 0.0f);
    for (size_t first = 0; first < slots; first += perLayer) {
        std::fill(layer.begin(), layer.end(), 0.0f);
        for (size_t slot = first; slot < std::min(slots, first + perLayer); ++slot) {
            const Int3 a = atlas.brickOf(slot);
            const float* src = rgb.data() + slot * size_t(kBrickVoxels) * 3;
            for (int z = 0; z < kBrickSide; ++z)
                for (int y = 0; y < kBrickSide; ++y) {
                    float* dst = layer.data() + ((size_t(z) * size_t(texels.y) + size_t(a.y * kBrickSide + y)) * size_t(texels.x) +
                                                 size_t(a.x * kBrickSide)) * 3;
                    std::copy_n(src + size_t((z * kBrickSide + y) * kBrickSide) * 3, kBrickSide * 3, dst);
                }
        }
        const int z0 = atlas.brickOf(first).z * kBrickSide;
        glTextureSubImage3D(tex.id(), 0, 0, 0, z0, texels.x, texels.y, kBrickSide, GL_RGB, GL_FLOAT, layer.data());
    }
    return tex;
}

/// The r32ui table from each brick to its atlas brick (inactive: the background's, 0).
gl::Texture uploadBrickTable(const BrickLayout& bricks, const Atlas& atlas) {
    std::vector<uint32_t> packed(bricks.slotTable().size());
    for (size_t i = 0; i < packed.size(); ++i) {
        const Int3 a = atlas.brickOf(bricks.slotTable()[i]);
        packed[i] = uint32_t(a.x) | uint32_t(a.y) << layout::kAtlasBits | uint32_t(a.z) << (2 * layout::kAtlasBits);
    }
    const Int3 n = bricks.brickDims();
    gl::Texture tex = gl::createTexture(GL_TEXTURE_3D, "brick-table");
    glTextureStorage3D(tex.id(), 1, GL_R32UI, n.x, n.y, n.z);
    // An integer texture with a linear filter is incomplete, and reads 0.
    glTextureParameteri(tex.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(tex.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage3D(tex.id(), 0, 0, 0, 0, n.x, n.y, n.z, GL_RED_INTEGER, GL_UNSIGNED_INT, packed.data());
    return tex;
}

}  // namespace

struct GpuVolume::Textures {
    gl::Texture extinction, albedo, emission, occupancy, brickTable;
};

GpuVolume::GpuVolume(const Volume& volume) : m_textures(std::make_unique<Textures>()) { upload(volume); }
GpuVolume::~GpuVolume() = default;

bool GpuVolume::hasAlbedo() const { return bool(m_textures->albedo); }
bool GpuVolume::hasEmission() const { return bool(m_textures->emission); }
unsigned GpuVolume::extinctionTexture() const { return m_textures->extinction.id(); }
unsigned GpuVolume::albedoTexture() const { return m_textures->albedo.id(); }
unsigned GpuVolume::emissionTexture() const { return m_textures->emission.id(); }
unsigned GpuVolume::occupancyTexture() const { return m_textures->occupancy.id(); }
unsigned GpuVolume::brickTableTexture() const { return m_textures->brickTable.id(); }

void GpuVolume::upload(const Volume& volume) {
    volume.validate();
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &maxSize);
    const Int3 d = volume.dims();
    const BrickLayout* bricks = volume.bricks();
    const Int3 bd = bricks ? bricks->brickDims() : Int3{};
    if (bricks ? (bd.x > maxSize || bd.y > maxSize || bd.z > maxSize) : (d.x > maxSize || d.y > maxSize || d.z > maxSize)) {
        throw GpuError("GpuVolume: " + std::to_string(d.x) + "x" + std::to_string(d.y) + "x" +
                       std::to_string(d.z) + " exceeds this GPU's 3D texture limit of " + std::to_string(maxSize));
    }
    const auto& ext = volume.extinction();
    const size_t hash = std::hash<std::string_view>()(
        std::string_view(reinterpret_cast<const char*>(ext.data()), ext.size() * sizeof(float)));
    Textures& t = *m_textures;
    const size_t layoutHash = bricks ? tableHash(*bricks) : 0;
    const bool sameLayout = bricks ? (m_sparse && layoutHash == m_tableHash && bricks->offset() == m_sparseOffset) : !m_sparse;
    const bool sameExtinction = t.extinction && d == m_dims && hash == m_extinctionHash && sameLayout;
    m_dims = d;
    m_sparse = bricks != nullptr;
    std::optional<Atlas> atlas;
    m_storedVoxels = volume.storedVoxels();
    if (bricks) {
        atlas = Atlas::forSlots(bricks->slots(), maxSize);
        m_sparseOffset = bricks->offset();
        const auto [lo, hi] = bricks->activeVoxelBox();
        m_activeBox = {{std::max(lo.x - 1, 0), std::max(lo.y - 1, 0), std::max(lo.z - 1, 0)},
                       {std::min(hi.x + 1, d.x - 1), std::min(hi.y + 1, d.y - 1), std::min(hi.z + 1, d.z - 1)}};
        if (!sameLayout) {
            t.brickTable = uploadBrickTable(*bricks, *atlas);
            m_tableHash = layoutHash;
        }
    } else {
        m_sparseOffset = {0, 0, 0};
        m_activeBox = {{0, 0, 0}, {d.x - 1, d.y - 1, d.z - 1}};
        t.brickTable = gl::Texture();
    }
    auto upload = [&](const std::vector<float>& rgb, const char* label) {
        return bricks ? uploadAtlas(rgb, *atlas, bricks->slots(), label) : uploadRgb(rgb, d, label);
    };
    m_worldFromIndex = volume.worldFromIndex();
    m_brickDims = {(d.x + layout::kBrickSize - 1) / layout::kBrickSize,
                   (d.y + layout::kBrickSize - 1) / layout::kBrickSize,
                   (d.z + layout::kBrickSize - 1) / layout::kBrickSize};
    if (!sameExtinction) {
        t.extinction = upload(volume.extinction(), "extinction");
        m_extinctionHash = hash;
        m_extinctionIsGrey = Volume::isGrey(ext);
        m_maxExtinction = maxComponent(Volume::range(ext).second);
        m_extinctionVersion = g_nextVersion++;
        t.occupancy = gl::createTexture(GL_TEXTURE_3D, "occupancy");
        glTextureStorage3D(t.occupancy.id(), 1, GL_R32F, m_brickDims.x, m_brickDims.y, m_brickDims.z);
    }
    t.albedo = volume.hasAlbedo() ? upload(volume.albedo(), "albedo") : gl::Texture();
    t.emission = volume.hasEmission() ? upload(volume.emission(), "emission") : gl::Texture();
    const size_t gridTexels = bricks ? size_t(atlas->bricks.volume()) * kBrickVoxels : size_t(d.volume());
    m_deviceBytes = gridTexels * 12 * (1 + size_t(volume.hasAlbedo()) + size_t(volume.hasEmission())) +
                    size_t(m_brickDims.volume()) * 4 + (bricks ? bricks->slotTable().size() * 4 : 0);
    m_refraction = RefractiveGrid::of(volume);  // paths are cached under its content's hash
    m_maxEmission = volume.hasEmission() ? maxComponent(Volume::range(volume.emission()).second) : 0.0f;
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("GpuVolume: out of GPU memory uploading the volume");
}

}  // namespace volstyle::core

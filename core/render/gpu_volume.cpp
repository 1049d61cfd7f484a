#include "core/render/gpu_volume.h"

#include <atomic>
#include <string_view>

#include "core/base/errors.h"
#include "core/render/curved_paths.h"
#include "core/gl/object.h"
#include "core/shaders/layout.h"

namespace volstyle::core {
namespace {

std::atomic<uint64_t> g_nextVersion{1};

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

}  // namespace

struct GpuVolume::Textures {
    gl::Texture extinction, albedo, emission, occupancy;
};

GpuVolume::GpuVolume(const Volume& volume) : m_textures(std::make_unique<Textures>()) { upload(volume); }
GpuVolume::~GpuVolume() = default;

bool GpuVolume::hasAlbedo() const { return bool(m_textures->albedo); }
bool GpuVolume::hasEmission() const { return bool(m_textures->emission); }
unsigned GpuVolume::extinctionTexture() const { return m_textures->extinction.id(); }
unsigned GpuVolume::albedoTexture() const { return m_textures->albedo.id(); }
unsigned GpuVolume::emissionTexture() const { return m_textures->emission.id(); }
unsigned GpuVolume::occupancyTexture() const { return m_textures->occupancy.id(); }

void GpuVolume::upload(const Volume& volume) {
    volume.validate();
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &maxSize);
    const Int3 d = volume.dims();
    if (d.x > maxSize || d.y > maxSize || d.z > maxSize) {
        throw GpuError("GpuVolume: " + std::to_string(d.x) + "x" + std::to_string(d.y) + "x" +
                       std::to_string(d.z) + " exceeds this GPU's 3D texture limit of " + std::to_string(maxSize));
    }
    const auto& ext = volume.extinction();
    const size_t hash = std::hash<std::string_view>()(
        std::string_view(reinterpret_cast<const char*>(ext.data()), ext.size() * sizeof(float)));
    Textures& t = *m_textures;
    const bool sameExtinction = t.extinction && d == m_dims && hash == m_extinctionHash;
    m_dims = d;
    m_worldFromIndex = volume.worldFromIndex();
    m_brickDims = {(d.x + layout::kBrickSize - 1) / layout::kBrickSize,
                   (d.y + layout::kBrickSize - 1) / layout::kBrickSize,
                   (d.z + layout::kBrickSize - 1) / layout::kBrickSize};
    if (!sameExtinction) {
        t.extinction = uploadRgb(volume.extinction(), d, "extinction");
        m_extinctionHash = hash;
        m_extinctionIsGrey = Volume::isGrey(ext);
        m_maxExtinction = maxComponent(Volume::range(ext).second);
        m_extinctionVersion = g_nextVersion++;
        t.occupancy = gl::createTexture(GL_TEXTURE_3D, "occupancy");
        glTextureStorage3D(t.occupancy.id(), 1, GL_R32F, m_brickDims.x, m_brickDims.y, m_brickDims.z);
    }
    t.albedo = volume.hasAlbedo() ? uploadRgb(volume.albedo(), d, "albedo") : gl::Texture();
    t.emission = volume.hasEmission() ? uploadRgb(volume.emission(), d, "emission") : gl::Texture();
    m_refraction = RefractiveGrid::of(volume);  // paths are cached under its content's hash
    m_maxEmission = volume.hasEmission() ? maxComponent(Volume::range(volume.emission()).second) : 0.0f;
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("GpuVolume: out of GPU memory uploading the volume");
}

}  // namespace volstyle::core

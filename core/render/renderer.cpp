#include "core/render/renderer.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>

#include "core/errors.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

/// A light-depth volume and what it was computed from.
struct Renderer::LightVolume {
    uint64_t extinctionVersion = 0;
    Vec3d direction;
    double stepVoxels = 0;
    bool exactTraversal = false;
    Int3 dims;
    gl::Texture texture;
    uint64_t lastUsedFrame = 0;
};

namespace {

layout::Float4 f4(const Vec3d& v, double w = 0) { return {float(v.x), float(v.y), float(v.z), float(w)}; }
layout::Int4 i4(Int3 v, int w = 0) { return {v.x, v.y, v.z, w}; }

layout::Float4x4 toGl(const Mat4& m) {
    layout::Float4x4 r;
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) r.m[c * 4 + row] = float(m(row, c));  // column-major
    return r;
}

/// Everything a march needs that does not depend on the camera.
layout::MarchParams volumeParams(const GpuVolume& volume, const RenderSettings& settings) {
    layout::MarchParams p;
    p.indexFromWorld = toGl(volume.worldFromIndex().inverseAffine());
    p.dims = i4(volume.dims());
    p.brickDims = i4(volume.brickDims());
    p.march = {float(settings.stepVoxels), float(settings.terminationThreshold), 0, 0};
    return p;
}

void dispatch3D(Int3 n) {
    const int g = layout::kWorkgroup3D;
    glDispatchCompute(GLuint((n.x + g - 1) / g), GLuint((n.y + g - 1) / g), GLuint((n.z + g - 1) / g));
}

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// The largest phase-function value: 1/4π, or HG at cos = −1 (pbrt's sign puts its peak there).
double maxPhase(const Phase& phase) {
    const double inv4pi = 1.0 / (4.0 * std::numbers::pi);
    if (phase.type == PhaseType::Isotropic) return inv4pi;
    double g = std::abs(phase.g);
    return inv4pi * (1 + g) / ((1 - g) * (1 - g));
}

double maxValue(const Image& image) {
    double m = 0;
    for (size_t i = 0; i < image.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) m = std::max(m, double(image.rgba[4 * i + c]));
    return m;
}

}  // namespace

double Renderer::radianceBound(const GpuVolume& volume, const Lighting& lighting) {
    // L_m ≤ max L_e + max ρ · Σ p_max E_l (ρ ≤ 1, T_l ≤ 1); the background is bounded by its max.
    double bound = volume.maxEmission();
    for (const auto& l : lighting.lights) bound += maxPhase(lighting.phase) * maxComponent(l.irradiance);
    if (lighting.background.environment) {
        if (lighting.background.environment != m_boundSource) {
            m_boundSource = lighting.background.environment;
            m_environmentMax = maxValue(*lighting.background.environment);
        }
        bound += m_environmentMax;
    } else {
        bound += maxComponent(lighting.background.color);
    }
    return bound;
}

Renderer::Renderer(gl::Context& context)
    : m_context(context),
      m_params(gl::createBuffer(sizeof(layout::MarchParams), nullptr, GL_DYNAMIC_STORAGE_BIT, "march-params")) {}

Renderer::~Renderer() = default;

void Renderer::clearCaches() { m_lightVolumes.clear(); }

const gl::Program& Renderer::program(const gl::ShaderBuilder& builder) {
    std::string key = builder.variantKey();
    auto it = m_programs.find(key);
    if (it == m_programs.end()) it = m_programs.emplace(key, builder.buildCompute()).first;
    return it->second;
}

void Renderer::uploadParams(const void* data, size_t bytes) {
    glNamedBufferSubData(m_params.id(), 0, GLsizeiptr(bytes), data);
    glBindBufferBase(GL_UNIFORM_BUFFER, layout::kBindingParams, m_params.id());
}

void Renderer::updateOccupancy(GpuVolume& volume, RenderStats& stats) {
    if (volume.occupancyVersion() == volume.extinctionVersion()) return;
    auto t0 = std::chrono::steady_clock::now();
    layout::MarchParams p = volumeParams(volume, RenderSettings{});
    uploadParams(&p, sizeof(p));
    glUseProgram(program(gl::ShaderBuilder("occupancy.comp")).id());
    glBindTextureUnit(layout::kUnitExtinction, volume.extinctionTexture());
    glBindImageTexture(layout::kImageUnitOut, volume.occupancyTexture(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatch3D(volume.brickDims());
    gl::barrierAfterComputeWrites();
    volume.markOccupancyCurrent();
    m_context.finish();  // rare: wait so the timing is this pass's own
    stats.occupancyMs += msSince(t0);
}

GLuint Renderer::lightDepthTexture(GpuVolume& volume, const DirectionalLight& light, const RenderSettings& march,
                                   RenderStats& stats) {
    const double stepVoxels = march.stepVoxels;
    const Vec3d dir = normalize(light.direction);
    for (auto& lv : m_lightVolumes) {
        if (lv->extinctionVersion == volume.extinctionVersion() && lv->direction == dir &&
            lv->stepVoxels == stepVoxels && lv->exactTraversal == march.exactTraversal && lv->dims == volume.dims()) {
            lv->lastUsedFrame = m_frame;
            return lv->texture.id();
        }
    }
    // Not cached: evict the least recently used once 2·kLightSlots volumes exist.
    auto t0 = std::chrono::steady_clock::now();
    std::unique_ptr<LightVolume> lv = std::make_unique<LightVolume>();
    if (m_lightVolumes.size() >= size_t(2 * layout::kLightSlots)) {
        auto oldest = std::min_element(m_lightVolumes.begin(), m_lightVolumes.end(),
                                       [](auto& a, auto& b) { return a->lastUsedFrame < b->lastUsedFrame; });
        m_lightVolumes.erase(oldest);
    }
    lv->extinctionVersion = volume.extinctionVersion();
    lv->direction = dir;
    lv->stepVoxels = stepVoxels;
    lv->exactTraversal = march.exactTraversal;
    lv->dims = volume.dims();
    lv->lastUsedFrame = m_frame;
    lv->texture = gl::createTexture(GL_TEXTURE_3D, "light-depth");
    const Int3 d = volume.dims();
    glTextureStorage3D(lv->texture.id(), 1, GL_RGBA32F, d.x, d.y, d.z);

    RenderSettings settings;
    settings.stepVoxels = stepVoxels;
    layout::MarchParams p = volumeParams(volume, settings);
    p.imageSize = {0, 0, 0, 0};  // z: the light index into lightDirection[]
    p.lightDirection[0] = f4(dir);
    uploadParams(&p, sizeof(p));
    glUseProgram(program(gl::ShaderBuilder("light_depth.comp").define("VOLSTYLE_EXACT_TRAVERSAL", march.exactTraversal ? 1 : 0)).id());
    glBindTextureUnit(layout::kUnitExtinction, volume.extinctionTexture());
    glBindTextureUnit(layout::kUnitOccupancy, volume.occupancyTexture());
    glBindImageTexture(layout::kImageUnitOut, lv->texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatch3D(d);
    gl::barrierAfterComputeWrites();
    m_context.finish();  // rare: wait so the timing is this pass's own
    stats.lightMs += msSince(t0);
    stats.lightVolumesRecomputed++;
    GLuint id = lv->texture.id();
    m_lightVolumes.push_back(std::move(lv));
    return id;
}

GLuint Renderer::environmentTexture(const std::shared_ptr<const Image>& env) {
    if (env == m_environmentSource && m_environment) return m_environment.id();
    m_environment = gl::createTexture(GL_TEXTURE_2D, "environment");
    glTextureStorage2D(m_environment.id(), 1, GL_RGBA32F, env->width, env->height);
    glTextureSubImage2D(m_environment.id(), 0, 0, 0, env->width, env->height, GL_RGBA, GL_FLOAT, env->rgba.data());
    glTextureParameteri(m_environment.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(m_environment.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(m_environment.id(), GL_TEXTURE_WRAP_S, GL_REPEAT);        // longitude wraps
    glTextureParameteri(m_environment.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);  // poles clamp
    m_environmentSource = env;
    return m_environment.id();
}

Renderer::MarchSetup Renderer::prepareMarch(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                                            const RenderSettings& settings, RenderStats& stats) {
    ++m_frame;
    updateOccupancy(volume, stats);

    // Lights with zero irradiance add nothing: leave them out of the variant.
    std::vector<const DirectionalLight*> lights;
    for (const auto& l : lighting.lights)
        if (maxComponent(l.irradiance) > 0) lights.push_back(&l);
    MarchSetup setup;
    for (size_t i = 0; i < lights.size(); ++i)
        setup.lightTextures.push_back(lightDepthTexture(volume, *lights[i], settings, stats));

    // Camera and lighting parameters.
    layout::MarchParams& p = setup.params;
    p = volumeParams(volume, settings);
    const Camera::Frame f = camera.frame();
    p.eye = f4(camera.eye);
    p.camForward = f4(f.forward, std::tan(camera.fovYDeg * std::numbers::pi / 360.0));
    p.camRight = f4(f.right, double(camera.width) / double(camera.height));
    p.camUp = f4(f.up);
    p.rayRange = {float(camera.nearDist), float(std::min(camera.farDist, 3.0e38)), 0, 0};
    p.imageSize = {camera.width, camera.height, 0, 0};
    p.background = f4(lighting.background.color);
    p.phase = {lighting.phase.type == PhaseType::HenyeyGreenstein ? 1.0f : 0.0f, float(lighting.phase.g), 0, 0};
    for (size_t i = 0; i < lights.size(); ++i) {
        p.lightDirection[i] = f4(normalize(lights[i]->direction));
        p.lightIrradiance[i] = f4(lights[i]->irradiance);
    }
    p.march.z = float(radianceBound(volume, lighting));
    return setup;
}

void Renderer::bindMarch(const GpuVolume& volume, const Lighting& lighting, const MarchSetup& setup) {
    uploadParams(&setup.params, sizeof(setup.params));
    glBindTextureUnit(layout::kUnitExtinction, volume.extinctionTexture());
    glBindTextureUnit(layout::kUnitOccupancy, volume.occupancyTexture());
    if (lighting.background.environment)
        glBindTextureUnit(layout::kUnitEnvironment, environmentTexture(lighting.background.environment));
    for (size_t i = 0; i < setup.lightTextures.size(); ++i)
        glBindTextureUnit(GLuint(layout::kUnitLightDepth0 + i), setup.lightTextures[i]);
}

Image Renderer::render(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                       const RenderSettings& settings, RenderStats* statsOut) {
    VOLSTYLE_CHECK(m_context.isOwnedByThisThread(), ==, true);
    camera.validate();
    lighting.validate();
    settings.validate();
    auto t0 = std::chrono::steady_clock::now();
    RenderStats stats;
    MarchSetup setup = prepareMarch(volume, camera, lighting, settings, stats);

    // Pick the variant: passes for absent features are compiled out.
    const bool hasEnvironment = bool(lighting.background.environment);
    gl::ShaderBuilder builder("render.comp");
    builder.define("VOLSTYLE_HAS_EMISSION", volume.hasEmission() ? 1 : 0)
        .define("VOLSTYLE_HAS_ALBEDO", volume.hasAlbedo() ? 1 : 0)
        .define("VOLSTYLE_NUM_LIGHTS", (long long)setup.lightTextures.size())
        .define("VOLSTYLE_HAS_ENVIRONMENT", hasEnvironment ? 1 : 0)
        .define("VOLSTYLE_SKIP_EMPTY", settings.skipEmptySpace ? 1 : 0)
        .define("VOLSTYLE_HW_FILTER", settings.hardwareFilter ? 1 : 0)
        .define("VOLSTYLE_EXACT_TRAVERSAL", settings.exactTraversal ? 1 : 0);
    glUseProgram(program(builder).id());
    bindMarch(volume, lighting, setup);
    if (volume.hasAlbedo()) glBindTextureUnit(layout::kUnitAlbedo, volume.albedoTexture());
    if (volume.hasEmission()) glBindTextureUnit(layout::kUnitEmission, volume.emissionTexture());

    const size_t bytes = size_t(camera.width) * camera.height * 4 * sizeof(float);
    if (bytes > m_pixelBytes) {
        m_pixels = gl::createBuffer(bytes, nullptr, GL_DYNAMIC_STORAGE_BIT, "render-pixels");
        m_pixelBytes = bytes;
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingImageOut, m_pixels.id());

    // March every pixel, then read the image back.
    const int g = layout::kWorkgroup2D;
    m_timer.begin();
    glDispatchCompute(GLuint((camera.width + g - 1) / g), GLuint((camera.height + g - 1) / g), 1);
    m_timer.end();
    gl::barrierAfterComputeWrites();
    Image image(camera.width, camera.height);
    glGetNamedBufferSubData(m_pixels.id(), 0, GLsizeiptr(image.rgba.size() * sizeof(float)), image.rgba.data());
    stats.gpuMs = m_timer.elapsedMs();
    stats.totalMs = msSince(t0);
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("Renderer::render(): out of GPU memory");
    if (statsOut) *statsOut = stats;
    return image;
}

}  // namespace volstyle::core

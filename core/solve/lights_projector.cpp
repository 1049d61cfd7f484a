#include "core/solve/lights_projector.h"

#include <epoxy/gl.h>

#include <algorithm>

#include "core/base/errors.h"
#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/shaders/layout.h"

namespace volstyle::core {
namespace {

/// As the volume projector's: rays stop where forward and adjoint both can (project.comp).
constexpr float kLightsProjectorTermination = 1e-8f;

int groupsOf(int n) { return (n + layout::kWorkgroup2D - 1) / layout::kWorkgroup2D; }

}  // namespace

/// The adjoint's per-workgroup sums, grown as views are added.
struct LightsProjector::Sums {
    gl::Buffer buffer;
    size_t groups = 0;
};

LightsProjector::LightsProjector(GpuDevice& device, GpuVolume& volume, const Lighting& lighting, double stepVoxels)
    : m_device(device), m_volume(volume), m_lighting(lighting), m_step(stepVoxels), m_sums(std::make_unique<Sums>()) {
    if (!lighting.environment.active())
        throw InvalidArgument("lights: the lighting has no environment lobes (environment.lobes is 0)");
    // T holds the lobes alone, each at unit radiance while the light volumes are prepared.
    m_lighting.lights.clear();
    m_lighting.background = Background{};
    m_lighting.background.fromLobes = lighting.background.fromLobes;
    m_lighting.environment.map = nullptr;
    m_lighting.environment.strength = 1;
    m_lighting.environment.radiance.assign(size_t(lighting.environment.lobes), Vec3d(1.0));
    m_lobes = lighting.environment.lobes;
}

LightsProjector::~LightsProjector() = default;

void LightsProjector::addView(const Camera& camera, const WorkBudget& budget, std::shared_ptr<const Image> plate) {
    camera.validate();
    RenderSettings settings;
    settings.stepVoxels = m_step;
    RenderStats stats;
    Lighting lighting = m_lighting;
    lighting.background.plate = std::move(plate);  // hides the lobes' background (and is checked)
    View view{camera, prepareMarch(m_device, m_volume, camera, lighting, settings, stats, budget), m_pixelCount};
    m_lightVolumeMs += stats.lightMs;
    layout::MarchParams& p = view.setup.params;
    p.viewPixels = {int(m_pixelCount), 0, 0, 0};
    p.projectorCutoff = {kLightsProjectorTermination, 0, 0, 0};
    m_pixelCount += size_t(camera.width) * camera.height;
    m_views.push_back(std::move(view));
}

size_t LightsProjector::lightVolumeBytes() const {
    return m_views.empty() || !m_views.front().setup.lobes ? 0 : m_views.front().setup.lobes->bytes();
}

void LightsProjector::use(const View& v, bool adjoint) {
    gl::ShaderBuilder builder("lights_project.comp");
    builder.define("VOLSTYLE_ADJOINT", adjoint ? 1 : 0)
        .define("VOLSTYLE_HAS_LOBES", 1)
        .define("VOLSTYLE_BACKGROUND_LOBES", v.setup.backgroundLobes ? 1 : 0)
        .define("VOLSTYLE_HAS_ALBEDO", m_volume.hasAlbedo() ? 1 : 0)
        .define("VOLSTYLE_SKIP_EMPTY", 1);
    if (v.setup.paths) builder.define("VOLSTYLE_CURVED", 1);
    glUseProgram(m_device.program(forStorage(builder, m_volume)).id());
    bindMarch(m_device, m_volume, v.setup);
    if (m_volume.hasAlbedo()) glBindTextureUnit(layout::kUnitAlbedo, m_volume.albedoTexture());
}

void LightsProjector::forward(const std::vector<Vec3d>& radiance, GpuVector& pixels) {
    VOLSTYLE_CHECK(radiance.size(), ==, size_t(m_lobes));
    VOLSTYLE_CHECK(pixels.size(), ==, m_pixelCount);
    for (View& v : m_views) {
        if (!v.setup.lobes) continue;  // (never: every lobe is lit in m_lighting)
        for (int i = 0; i < m_lobes; ++i) v.setup.lobeParams.radiance[i] = {float(radiance[size_t(i)].x), float(radiance[size_t(i)].y), float(radiance[size_t(i)].z), 0};
        use(v, false);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingImageOut, pixels.id());
        glDispatchCompute(GLuint(groupsOf(v.camera.width)), GLuint(groupsOf(v.camera.height)), 1);
    }
    gl::barrierAfterComputeWrites();
}

std::vector<Vec3d> LightsProjector::adjoint(const GpuVector& residual) {
    VOLSTYLE_CHECK(residual.size(), ==, m_pixelCount);
    size_t groups = 0;
    for (const View& v : m_views) groups += size_t(groupsOf(v.camera.width)) * groupsOf(v.camera.height);
    const size_t bytes = std::max<size_t>(groups, 1) * layout::kLobeChunk * 4 * sizeof(float);
    if (groups > m_sums->groups) {
        m_sums->buffer = gl::createBuffer(bytes, nullptr, GL_DYNAMIC_STORAGE_BIT, "lobe-sums");
        m_sums->groups = groups;
    }
    std::vector<Vec3d> out(static_cast<size_t>(m_lobes));
    std::vector<float> sums(groups * layout::kLobeChunk * 4);
    for (int first = 0; first < m_lobes; first += layout::kLobeChunk) {
        const int count = std::min(layout::kLobeChunk, m_lobes - first);
        size_t firstGroup = 0;
        for (View& v : m_views) {
            v.setup.params.lobeKernel = {first, count, int(firstGroup), 0};
            use(v, true);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingResidual, residual.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingLobeSums, m_sums->buffer.id());
            glDispatchCompute(GLuint(groupsOf(v.camera.width)), GLuint(groupsOf(v.camera.height)), 1);
            firstGroup += size_t(groupsOf(v.camera.width)) * groupsOf(v.camera.height);
        }
        gl::barrierAfterComputeWrites();
        glGetNamedBufferSubData(m_sums->buffer.id(), 0, GLsizeiptr(sums.size() * sizeof(float)), sums.data());
        // The groups' sums, added in double (the last reduction level, on the host).
        for (size_t g = 0; g < groups; ++g)
            for (int k = 0; k < count; ++k) {
                const float* s = &sums[(g * layout::kLobeChunk + size_t(k)) * 4];
                out[size_t(first + k)] += Vec3d(s[0], s[1], s[2]);
            }
    }
    return out;
}

}  // namespace volstyle::core

#include "core/render/renderer.h"

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/render/chunked_dispatch.h"
#include "core/render/march_setup.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

/// The output pixels (grown as needed) and the GPU timer.
struct Renderer::Buffers {
    gl::Buffer pixels, layers;
    size_t pixelBytes = 0, layerBytes = 0;
    gl::GpuTimer timer;
};

Renderer::Renderer(GpuDevice& device) : m_device(device), m_buffers(std::make_unique<Buffers>()) {}
Renderer::~Renderer() = default;

Image Renderer::render(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                       const RenderSettings& settings, RenderStats* statsOut, const WorkBudget& budget) {
    return march(volume, camera, lighting, settings, statsOut, budget, nullptr);
}

RenderLayers Renderer::renderLayers(GpuVolume& volume, const Camera& camera, const Lighting& lighting,
                                    const RenderSettings& settings, RenderStats* statsOut, const WorkBudget& budget, bool withAlbedoOne) {
    RenderLayers layers;
    layers.beauty = march(volume, camera, lighting, settings, statsOut, budget, &layers, withAlbedoOne);
    return layers;
}

Image Renderer::march(GpuVolume& volume, const Camera& camera, const Lighting& lighting, const RenderSettings& settings,
                      RenderStats* statsOut, const WorkBudget& budget, RenderLayers* layers, bool withAlbedoOne) {
    VOLSTYLE_CHECK(m_device.isOwnedByThisThread(), ==, true);
    camera.validate();
    lighting.validate();
    settings.validate();
    const auto t0 = Clock::now();
    RenderStats stats;
    const MarchSetup setup = prepareMarch(m_device, volume, camera, lighting, settings, stats, budget);

    // Pick the variant: passes for absent features are compiled out.
    gl::ShaderBuilder builder("render.comp");
    builder.define("VOLSTYLE_HAS_EMISSION", volume.hasEmission() ? 1 : 0)
        .define("VOLSTYLE_HAS_ALBEDO", volume.hasAlbedo() ? 1 : 0)
        .define("VOLSTYLE_NUM_LIGHTS", (long long)setup.lightDepth.size())
        .define("VOLSTYLE_HAS_LOBES", setup.lobes ? 1 : 0)
        .define("VOLSTYLE_HAS_ENVIRONMENT", setup.environment ? 1 : 0)
        .define("VOLSTYLE_BACKGROUND_PLATE", setup.plate ? 1 : 0)
        .define("VOLSTYLE_BACKGROUND_LOBES", setup.backgroundLobes ? 1 : 0)
        .define("VOLSTYLE_SKIP_EMPTY", settings.skipEmptySpace ? 1 : 0)
        .define("VOLSTYLE_HW_FILTER", settings.hardwareFilter ? 1 : 0)
        .define("VOLSTYLE_EXACT_TRAVERSAL", settings.exactTraversal ? 1 : 0)
        .define("VOLSTYLE_LAYERS", layers ? 1 : 0)
        .define("VOLSTYLE_ALBEDO_ONE_LAYER", layers && withAlbedoOne ? 1 : 0);
    if (setup.paths) builder.define("VOLSTYLE_CURVED", 1);  // refracted rays (straight rays: the kernel unchanged)
    glUseProgram(m_device.program(forStorage(builder, volume)).id());
    bindMarch(m_device, volume, setup);  // dispatchChunked re-uploads the block per chunk
    if (volume.hasAlbedo()) glBindTextureUnit(layout::kUnitAlbedo, volume.albedoTexture());
    if (volume.hasEmission()) glBindTextureUnit(layout::kUnitEmission, volume.emissionTexture());

    Buffers& b = *m_buffers;
    const size_t bytes = size_t(camera.width) * camera.height * 4 * sizeof(float);
    if (bytes > b.pixelBytes) {
        b.pixels = gl::createBuffer(bytes, nullptr, GL_DYNAMIC_STORAGE_BIT, "render-pixels");
        b.pixelBytes = bytes;
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingImageOut, b.pixels.id());
    const int planeCount = withAlbedoOne ? layout::kRenderLayersWithAlbedoOne : layout::kRenderLayers;
    if (layers) {
        if (bytes * size_t(planeCount) > b.layerBytes) {
            b.layers = gl::createBuffer(bytes * size_t(planeCount), nullptr, GL_DYNAMIC_STORAGE_BIT, "render-layers");
            b.layerBytes = bytes * size_t(planeCount);
        }
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingLayersOut, b.layers.id());
    }

    // March every pixel, then read the image back.
    b.timer.begin();
    try {
        dispatchChunked(m_device, setup.params, {camera.width, camera.height, 1}, DispatchShape::Image, budget, "render's march");
    } catch (...) {
        b.timer.end();  // a query left open would fail the next render's begin()
        throw;
    }
    b.timer.end();
    gl::barrierAfterComputeWrites();
    Image image(camera.width, camera.height);
    glGetNamedBufferSubData(b.pixels.id(), 0, GLsizeiptr(bytes), image.rgba.data());
    if (layers) {
        Image* planes[layout::kRenderLayersWithAlbedoOne] = {&layers->medium, &layers->emission, &layers->scattering,
                                                             &layers->transmittance, &layers->background,
                                                             &layers->scatteringAtAlbedoOne};  // render.comp's order
        for (int k = 0; k < planeCount; ++k) {
            *planes[k] = Image(camera.width, camera.height);
            glGetNamedBufferSubData(b.layers.id(), GLintptr(bytes * size_t(k)), GLsizeiptr(bytes), planes[k]->rgba.data());
        }
    }
    stats.gpuMs = b.timer.elapsedMs();
    stats.totalMs = msSince(t0);
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory while rendering");
    if (statsOut) *statsOut = stats;
    return image;
}

}  // namespace volstyle::core

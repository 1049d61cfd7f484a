// Renders of a session on the GL thread (SPEC §3 "Concurrency", §9): single scattering, the
// translucent preview, a view (with its plate) and a running job's preview, all under the render
// budget.
#include <fmt/format.h>

#include "core/render/renderer.h"
#include "core/translucent/translucent_renderer.h"
#include "server/service/services.h"

namespace volstyle::server {

/// Texels the translucent slices fill per second on llvmpipe's two cores (TranslucentRenderer::
/// estimatedTexels; measured by tests/probe's 4096² case: 89 slices of 4096² + 2 × 4096² in 60 s,
/// 8e7/s, halved for a slower machine of the kind).
constexpr double kTranslucentTexelsPerSecond = 4e7;


core::Lighting VolumeService::viewLighting(Session& s, const SessionView& v) {
    core::Lighting l = m_ctx.lighting(s);
    if (v.background) l.background.plate = v.background;  // the view's plate
    return l;
}

core::RenderLayers VolumeService::renderOnGl(Session& s, const core::Camera& camera, const core::Lighting& lighting,
                                              bool layers) {
    return m_ctx.gl->run([&](core::GpuDevice& device) {
        const std::shared_ptr<core::GpuVolume> gpu = m_ctx.lockedSessionGpu(s);  // a commit meanwhile frees it after us
        return renderBudgeted(device, *gpu, camera, lighting, layers);
    });
}

core::RenderLayers VolumeService::renderBudgeted(core::GpuDevice& device, core::GpuVolume& gpu, const core::Camera& camera,
                                                  const core::Lighting& lighting, bool layers) {
    // Other sessions' renders and a solve's next iteration wait behind this one: bound it.
    const WorkBudget budget(m_ctx.limits.renderBudgetSeconds);
    if (layers) return m_ctx.renderer(device).renderLayers(gpu, camera, lighting, {}, nullptr, budget);
    core::RenderLayers out;
    out.beauty = m_ctx.renderer(device).render(gpu, camera, lighting, {}, nullptr, budget);
    return out;
}

core::RenderLayers VolumeService::render(Session& s, const core::Camera& camera, bool layers) {
    return renderOnGl(s, camera, m_ctx.lighting(s), layers);
}

core::Image VolumeService::renderTranslucent(Session& s, const core::Camera& camera, const core::TranslucentSettings& settings,
                                              core::Image* medium) {
    const core::Lighting l = m_ctx.lighting(s);
    // Estimated before it holds the GL thread (a 4096² render with a 4096² light buffer at 0.05
    // voxel slices ran 106 s, and every other session waited): the bound of every slice filling
    // the image and the light buffer, at the slower of this machine kind's measured rates.
    Int3 dims;
    {
        std::lock_guard lock(s.mutex);
        dims = s.volume.current.dims();
    }
    const double seconds = core::TranslucentRenderer::estimatedTexels(dims, camera, settings) / kTranslucentTexelsPerSecond;
    if (m_ctx.limits.renderBudgetSeconds > 0 && seconds > m_ctx.limits.renderBudgetSeconds)
        throw ApiError(ErrorCode::OverBudget,
                       fmt::format("this translucent render could take up to {:.0f} s, over the render budget of {:g} s (volstyle serve "
                                   "--render-budget); use fewer pixels, a smaller light_buffer or a larger slice_spacing",
                                   seconds, m_ctx.limits.renderBudgetSeconds));
    return m_ctx.gl->run([&](core::GpuDevice& device) {
        const std::shared_ptr<core::GpuVolume> gpu = m_ctx.lockedSessionGpu(s);
        if (!m_ctx.translucent) m_ctx.translucent = std::make_unique<core::TranslucentRenderer>(device);
        return m_ctx.translucent->render(*gpu, camera, l, settings, nullptr, medium, WorkBudget(m_ctx.limits.renderBudgetSeconds));
    });
}

core::RenderLayers VolumeService::renderView(Session& s, const std::string& viewId, bool layers) {
    const SessionView v = m_ctx.view(s, viewId);
    return renderOnGl(s, v.camera, viewLighting(s, v), layers);
}

core::Image VolumeService::renderPreview(const std::string& jobId, const std::string& viewId) {
    auto j = m_ctx.job(jobId);
    auto s = m_ctx.find(j->session);
    const SessionView v = m_ctx.view(*s, viewId);
    const core::Camera camera = v.camera;
    const core::Lighting light = viewLighting(*s, v);
    return m_ctx.gl->run([&](core::GpuDevice& device) {
        std::shared_ptr<core::GpuVolume> preview;
        {
            std::lock_guard lock(j->mutex);
            preview = j->preview;
        }
        if (!preview) preview = m_ctx.lockedSessionGpu(*s);
        return renderBudgeted(device, *preview, camera, light, /*layers=*/false).beauty;
    });
}

}  // namespace volstyle::server

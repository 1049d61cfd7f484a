// Renders of a session on the GL thread (SPEC §3 "Concurrency", §9): single scattering, the
// translucent preview, a view (with its plate) and a running job's preview, all under the render
// budget.
#include <fmt/format.h>

#include "core/render/renderer.h"
#include "core/translucent/translucent_renderer.h"
#include "server/service/session_service.h"

namespace volstyle::server {

/// Texels the translucent slices fill per second on llvmpipe's two cores (TranslucentRenderer::
/// estimatedTexels; measured by tests/probe's 4096² case: 89 slices of 4096² + 2 × 4096² in 60 s,
/// 8e7/s, halved for a slower machine of the kind).
constexpr double kTranslucentTexelsPerSecond = 4e7;

using protocol::ApiError;
using protocol::ErrorCode;

core::Renderer& SessionService::renderer(core::GpuDevice& device) {
    if (!m_renderer) m_renderer = std::make_unique<core::Renderer>(device);
    return *m_renderer;
}

std::shared_ptr<core::GpuVolume> SessionService::sessionGpu(Session& s) {
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    if (!s.gpu) s.gpu = std::make_shared<core::GpuVolume>(s.volume);
    return s.gpu;
}

std::shared_ptr<core::GpuVolume> SessionService::lockedSessionGpu(Session& s) {
    // The lock covers only finding (or uploading) the GPU copy, not the render: reads of the
    // session (a VDB download, its JSON) never wait for GL work. Locking on the GL thread is safe
    // even between a solve's iterations: the solve holds no session lock then.
    std::lock_guard lock(s.mutex);
    return sessionGpu(s);
}

core::Lighting SessionService::viewLighting(Session& s, const SessionView& v) {
    core::Lighting l = lighting(s);
    if (v.background) l.background.plate = v.background;  // the view's plate
    return l;
}

core::RenderLayers SessionService::renderOnGl(Session& s, const core::Camera& camera, const core::Lighting& lighting,
                                              bool layers) {
    return m_gl->run([&](core::GpuDevice& device) {
        const std::shared_ptr<core::GpuVolume> gpu = lockedSessionGpu(s);  // a commit meanwhile frees it after us
        return renderBudgeted(device, *gpu, camera, lighting, layers);
    });
}

core::RenderLayers SessionService::renderBudgeted(core::GpuDevice& device, core::GpuVolume& gpu, const core::Camera& camera,
                                                  const core::Lighting& lighting, bool layers) {
    // Other sessions' renders and a solve's next iteration wait behind this one: bound it.
    const WorkBudget budget(m_limits.renderBudgetSeconds);
    if (layers) return renderer(device).renderLayers(gpu, camera, lighting, {}, nullptr, budget);
    core::RenderLayers out;
    out.beauty = renderer(device).render(gpu, camera, lighting, {}, nullptr, budget);
    return out;
}

core::RenderLayers SessionService::render(Session& s, const core::Camera& camera, bool layers) {
    return renderOnGl(s, camera, lighting(s), layers);
}

core::Image SessionService::renderTranslucent(Session& s, const core::Camera& camera, const core::TranslucentSettings& settings,
                                              core::Image* medium) {
    const core::Lighting l = lighting(s);
    // Estimated before it holds the GL thread (a 4096² render with a 4096² light buffer at 0.05
    // voxel slices ran 106 s, and every other session waited): the bound of every slice filling
    // the image and the light buffer, at the slower of this machine kind's measured rates.
    Int3 dims;
    {
        std::lock_guard lock(s.mutex);
        dims = s.volume.dims();
    }
    const double seconds = core::TranslucentRenderer::estimatedTexels(dims, camera, settings) / kTranslucentTexelsPerSecond;
    if (m_limits.renderBudgetSeconds > 0 && seconds > m_limits.renderBudgetSeconds)
        throw ApiError(ErrorCode::OverBudget,
                       fmt::format("this translucent render could take up to {:.0f} s, over the render budget of {:g} s (volstyle serve "
                                   "--render-budget); use fewer pixels, a smaller light_buffer or a larger slice_spacing",
                                   seconds, m_limits.renderBudgetSeconds));
    return m_gl->run([&](core::GpuDevice& device) {
        const std::shared_ptr<core::GpuVolume> gpu = lockedSessionGpu(s);
        if (!m_translucent) m_translucent = std::make_unique<core::TranslucentRenderer>(device);
        return m_translucent->render(*gpu, camera, l, settings, nullptr, medium, WorkBudget(m_limits.renderBudgetSeconds));
    });
}

core::RenderLayers SessionService::renderView(Session& s, const std::string& viewId, bool layers) {
    const SessionView v = view(s, viewId);
    return renderOnGl(s, v.camera, viewLighting(s, v), layers);
}

core::Image SessionService::renderPreview(const std::string& jobId, const std::string& viewId) {
    auto j = job(jobId);
    auto s = find(j->session);
    const SessionView v = view(*s, viewId);
    const core::Camera camera = v.camera;
    const core::Lighting light = viewLighting(*s, v);
    return m_gl->run([&](core::GpuDevice& device) {
        std::shared_ptr<core::GpuVolume> preview;
        {
            std::lock_guard lock(j->mutex);
            preview = j->preview;
        }
        if (!preview) preview = lockedSessionGpu(*s);
        return renderBudgeted(device, *preview, camera, light, /*layers=*/false).beauty;
    });
}

}  // namespace volstyle::server

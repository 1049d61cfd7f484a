#include "server/service/live_stream_pipeline.h"

#include "core/gl/readback_ring.h"
#include "server/runtime/gl_executor.h"

namespace volstyle::server {

/// Two slots: the frame being encoded and the one rendering.
constexpr int kLiveReadbackSlots = 2;

LiveStreamPipeline::LiveStreamPipeline(GlExecutor& gl, std::shared_ptr<Session> session) : m_gl(gl), m_session(std::move(session)) {}

LiveStreamPipeline::~LiveStreamPipeline() {
    if (next.valid()) {
        try {
            release(next.get());
        } catch (...) {  // a frame nobody will see
        }
    }
    if (!m_ring) return;
    // GL objects go on the GL thread. If it is gone (the server stopping), so is its context:
    // the ring is left as it is rather than freed without one.
    core::gl::ReadbackRing* ring = m_ring.release();
    try {
        m_gl.run([ring](core::GpuDevice&) { delete ring; });
    } catch (...) {
    }
}

core::gl::ReadbackRing& LiveStreamPipeline::ring() {
    if (!m_ring) m_ring = std::make_unique<core::gl::ReadbackRing>(kLiveReadbackSlots);
    return *m_ring;
}

void LiveStreamPipeline::release(const RenderedLiveFrame& f) {
    if (f.frame.displaySlot >= 0 && m_ring) m_ring->release(f.frame.displaySlot);
}

}  // namespace volstyle::server

#pragma once
/// \file live_stream_pipeline.h
/// One live stream's frames in flight (issue #40). A frame comes back from the GPU as display
/// bytes in a read-back slot (core::gl::ReadbackRing: persistently mapped buffers and a fence),
/// and while this stream's thread encodes and sends it, the GL thread already renders the newest
/// revision into the other slot. StylizerService::nextLiveFrame drives it; the HTTP route owns one
/// per open stream.

#include <chrono>
#include <cstdint>
#include <future>
#include <memory>

#include "core/stylize/stylizer.h"

namespace volstyle::core::gl {
class ReadbackRing;
}

namespace volstyle::server {

class GlExecutor;
struct Session;

/// A frame rendered for a live stream, not yet encoded: its display bytes hold a slot of the
/// pipeline's ring until encoded (or `frame.frame` holds the picture: a TF with anchored
/// constraints is applied on the CPU).
struct RenderedLiveFrame {
    uint64_t revision = 0;
    core::StylizedFrame frame;
    int width = 0, height = 0;
    double renderMs = 0;  ///< on the GL thread: the passes and the read-back
};

class LiveStreamPipeline {
public:
    LiveStreamPipeline(GlExecutor& gl, std::shared_ptr<Session> session);
    /// Waits for a render in flight and frees the slots on the GL thread.
    ~LiveStreamPipeline();
    LiveStreamPipeline(const LiveStreamPipeline&) = delete;
    LiveStreamPipeline& operator=(const LiveStreamPipeline&) = delete;

    Session& session() const { return *m_session; }
    const std::shared_ptr<Session>& sessionPtr() const { return m_session; }
    /// The ring the frames come back in (made at first use on the GL thread: call it there).
    core::gl::ReadbackRing& ring();
    /// Hands a rendered frame's slot back (any thread; nothing when it holds none).
    void release(const RenderedLiveFrame& f);

    /// The render started while the previous frame was encoded (valid() when there is one), and
    /// the revision it renders.
    std::future<RenderedLiveFrame> next;
    uint64_t nextRevision = 0;
    /// The revision whose render failed last (0: none): what the stream reports as failed, and the
    /// one it waits past (a newer revision is rendered, not skipped).
    uint64_t failedRevision = 0;

private:
    GlExecutor& m_gl;
    std::shared_ptr<Session> m_session;
    std::unique_ptr<core::gl::ReadbackRing> m_ring;
};

}  // namespace volstyle::server

#pragma once
/// \file render_stats.h
/// What one frame did, for benchmarks and logs. GL-free.

namespace volstyle::core {

struct RenderStats {
    double gpuMs = 0;          ///< the render dispatch (GPU timer query)
    double lightMs = 0;        ///< light-depth volumes recomputed this frame (0 when cached)
    double occupancyMs = 0;    ///< occupancy recomputed this frame (0 when cached)
    double totalMs = 0;        ///< wall clock including readback
    int lightVolumesRecomputed = 0;
    double refractionMs = 0;   ///< refracted rays traced this frame (0 when cached or straight)
};

}  // namespace volstyle::core

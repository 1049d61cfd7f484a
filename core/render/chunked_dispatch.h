#pragma once
/// \file chunked_dispatch.h
/// Dispatches a march kernel in chunks so that a bounded request (WorkBudget) can stop between
/// them: a 256³ light-depth pass is one dispatch of minutes on llvmpipe, and GL cannot interrupt
/// a dispatch. Each chunk is whole slabs (z for volume kernels, rows for image kernels) of about
/// kChunkInvocations cells, offset by MarchParams::dispatchOffset, which the kernel adds to
/// gl_GlobalInvocationID. An unbounded budget dispatches once, as before. GL thread only.

#include "core/base/work_budget.h"
#include "core/gpu/gpu_device.h"
#include "core/math/vec.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

/// About a quarter of a second of light-depth marching on llvmpipe: the budget overshoots by at
/// most that, and on a GPU a 480² image or a 64³ volume is still a single chunk.
inline constexpr long long kChunkInvocations = 1 << 18;

enum class DispatchShape {
    Volume,  ///< one invocation per voxel of `cells`, kWorkgroup3D³ groups, chunked along z
    Image,   ///< one invocation per pixel of cells.x × cells.y, kWorkgroup2D² groups, chunked along y
};

/// Runs the bound program over `cells`, uploading `params` (with its dispatchOffset set) before
/// each chunk; between chunks waits for the GPU and calls budget.check(pass, fraction done).
/// `chunkInvocations`: cells per chunk, for kernels whose invocations cost more than a march's
/// (light_depth.comp marches a whole row of nodes per invocation).
void dispatchChunked(GpuDevice& device, layout::MarchParams params, Int3 cells, DispatchShape shape,
                     const WorkBudget& budget, const char* pass, long long chunkInvocations = kChunkInvocations);

}  // namespace volstyle::core

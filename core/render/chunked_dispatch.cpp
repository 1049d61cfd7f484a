#include "core/render/chunked_dispatch.h"

#include <epoxy/gl.h>

#include <algorithm>

namespace volstyle::core {

void dispatchChunked(GpuDevice& device, layout::MarchParams params, Int3 cells, DispatchShape shape,
                     const WorkBudget& budget, const char* pass, long long chunkInvocations) {
    const bool volume = shape == DispatchShape::Volume;
    const int group = volume ? layout::kWorkgroup3D : layout::kWorkgroup2D;
    const long long sliceCells = volume ? (long long)cells.x * cells.y : cells.x;
    const int extent = volume ? cells.z : cells.y;  // the axis chunks cut
    // Slabs per chunk: a multiple of the group size, at least one group.
    int slabs = extent;
    if (budget.bounded())
        slabs = int(std::clamp<long long>(budget.chunkInvocations(chunkInvocations) / std::max(sliceCells, 1LL) / group * group, group,
                                          ((extent + group - 1) / group) * group));
    const auto groups = [group](int n) { return GLuint((n + group - 1) / group); };
    for (int first = 0; first < extent; first += slabs) {
        if (first > 0) {
            device.finish();  // the previous chunk is done: now the time it took has passed
            budget.check(pass, double(first) / extent);
        }
        const int count = std::min(slabs, extent - first);
        params.dispatchOffset = {0, volume ? 0 : first, volume ? first : 0, 0};
        device.setParams(params);
        if (volume) glDispatchCompute(groups(cells.x), groups(cells.y), groups(count));
        else glDispatchCompute(groups(cells.x), groups(count), 1);
    }
}

}  // namespace volstyle::core

#pragma once
/// \file host_vector_ops.h
/// vector_ops.comp's kernels on the host, for vectors it can map in place (GpuVector's
/// `hostMapped`: on a CPU rasterizer, issue #40). There a dispatch costs more in set-up and
/// synchronisation than the few megabytes it touches, and the solver's iterations were mostly
/// vector work once W and Wᵀ ran on the host (host_products.h). The arithmetic is the shader's:
/// updates in float, reductions in float64 (summed in another order: rounding apart). GPUs keep
/// vector_ops.comp. GL thread only.

#include <cstdint>
#include <utility>
#include <vector>

#include "core/solve/gpu_vector.h"

namespace volstyle::core {

/// One kernel's operands, as VectorOps::run gathers them.
struct HostVectorOp {
    int op = 0;  ///< a VOLSTYLE_OP_* value (layout.h)
    const GpuVector* x = nullptr;
    const GpuVector* y = nullptr;  ///< its buffer is written by the element-wise kernels, as the shader's binding is
    const GpuVector* z = nullptr;
    float alpha[3] = {0, 0, 0};
    Bounds bounds;
    size_t first = 0, count = 0;        ///< positions in `list` (or elements) the kernel covers
    const uint32_t* list = nullptr;      ///< the support's elements, or null
    Int3 dims;                           ///< the Laplacian's grid
    size_t laplacianCells = 0;           ///< cells per block of the Laplacian
    std::vector<std::pair<size_t, size_t>> segments;  ///< DOT_SEGMENTS: (first position, count) each
};

/// Whether the host can run `op` (every operand mapped in place; the sparse Laplacian stays on the GPU).
bool hostCanRun(const HostVectorOp& op, bool sparseLaplacian);

/// Runs the kernel; a reduction returns its partials as vector_ops.comp writes them (4 doubles a
/// group: here one group, or one a segment), the others nothing.
std::vector<double> runOnHost(const HostVectorOp& op);

}  // namespace volstyle::core

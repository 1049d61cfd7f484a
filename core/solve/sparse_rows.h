#pragma once
/// \file sparse_rows.h
/// One view's rows of W kept on the GPU, and their transpose. For emission, albedo and
/// extinction solves W is fixed for the whole solve: its weights (transmittance, opacity,
/// in-scattering, segment lengths) depend only on the extinction, the lighting and the camera,
/// none of which a solve changes. Written once by project.comp's VOLSTYLE_ROWS passes
/// (Projector::cacheRows), the rows make W a gather over about 4 entries per cell a ray crosses,
/// and the columns make Wᵀ a gather too (no atomics); both in sparse_project.comp. GL thread only.

#include <cstddef>

#include "core/gl/object.h"
#include "core/gpu/gpu_device.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/solve/gpu_vector.h"
#include "core/scene/solve_types.h"
#include "core/volume/volume.h"

namespace volstyle::core {

struct SparseRows {
    gl::Buffer rowStart, rowIndex, rowWeight;  ///< per pixel: first entry; per entry: element, weight(s)
    gl::Buffer colStart, colIndex, colWeight;  ///< per element: first entry; per entry: pixel, weight(s)
    size_t rows = 0, columns = 0, entries = 0;
    int channels = 3;  ///< weights per entry: 1 (grey) or 3 (rgb)
    bool hostMapped = false;  ///< the start, index and weight buffers can be mapped (host_columns.h, host_products.h)
    double buildMs = 0;       ///< what writing them took (what a miss in SolveCache costs again)
};

/// GPU bytes a view's rows and columns take.
size_t sparseRowsBytes(size_t rows, size_t columns, size_t entries, int channels);

/// 1 where every weight of W has r = g = b (grey extinction, and grey lights when the unknowns
/// include albedo), else 3: a grey cache is a third of the size and of the loads.
int weightChannels(const Volume& volume, const Lighting& lighting, Unknown unknown);

/// pixels[pixelOffset + p] = (W a)_p for the view's pixels p (with `only`: those in it).
void sparseForward(GpuDevice& device, const SparseRows& rows, const GpuVector& a, GpuVector& pixels, size_t pixelOffset,
                   const Support* only = nullptr);
/// a += Wᵀ r over the view's pixels r = pixels[pixelOffset ..] (with `only`: for its elements).
void sparseAdjointAdd(GpuDevice& device, const SparseRows& rows, const GpuVector& pixels, size_t pixelOffset, GpuVector& a,
                      const Support* only = nullptr);

/// One view within rows merged over every view (Projector::mergeRows, issue #40): its rows are
/// the merged rows [view.first, view.first + view.count), which are its pixels, and its columns
/// are the merged columns' entries for those pixels.
/// pixels[p] = (W a)_p for the range's pixels p (with `only`: those in it).
void sparseForwardRange(GpuDevice& device, const SparseRows& merged, Range view, const GpuVector& a, GpuVector& pixels,
                        const Support* only = nullptr);
/// a += W_vᵀ r: the merged columns' entries of the range's pixels of r = pixels (with `only`: for its elements).
void sparseAdjointAddRange(GpuDevice& device, const SparseRows& merged, Range view, const GpuVector& pixels, GpuVector& a,
                           const Support* only = nullptr);

/// pixels[pixelOffset + p] += (W c)_p by the view's columns (with `only`: those elements'), reading
/// only the columns of elements where c ≠ 0 and adding atomically: cheap when c is 0 almost
/// everywhere (the unknowns a bound clamped), where a row gather would read every entry. With
/// GL_NV_shader_atomic_float (`floatAtomics`) or a compare-and-swap loop.
void sparseForwardByColumns(GpuDevice& device, const SparseRows& rows, const GpuVector& c, GpuVector& pixels, size_t pixelOffset,
                            const Support* only, bool floatAtomics);

/// Sets marks[e] = 1 for every element e the view's rows of `list`'s pixels have an entry for
/// (columns = false; `marks` over the elements), or marks[pixelOffset + p] = 1 for every pixel p
/// the columns of `list`'s elements have one for (columns = true; `marks` over the pixels).
void sparseMark(GpuDevice& device, const SparseRows& rows, bool columns, const Support& list, size_t pixelOffset,
                GpuVector& marks);

}  // namespace volstyle::core

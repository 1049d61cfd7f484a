#pragma once
/// \file host_products.h
/// W a and Wᵀ r from a view's (or the merged) rows, computed by the host on a CPU rasterizer
/// (issue #40). There the rows, the columns and the solver's vectors are the process's own memory
/// (mapped in place, host_columns.h), and a plain loop over them on every core gathers at a few
/// ns an entry where sparse_project.comp's lanes, which diverge over rows of unequal length and
/// gather one lane at a time, take several times that. GPUs keep sparse_project.comp. The sums run
/// in the same order as the shader's: the results agree to float rounding. GL thread only.

#include <cstddef>

#include "core/solve/gpu_vector.h"
#include "core/solve/sparse_rows.h"

namespace volstyle::core {

/// Whether the host can apply `rows` to these vectors in place (all mapped storage).
bool hostCanApply(const SparseRows& rows, const GpuVector& a, const GpuVector& pixels);

/// pixels[pixelOffset + p] = (W a)_p over the rows [view.first, view.first + view.count) of
/// `rows` (the view's pixels p = 0, 1, …; with `only`: those of its elements in the range).
void hostForward(const SparseRows& rows, Range view, const GpuVector& a, GpuVector& pixels, size_t pixelOffset,
                 const Support* only);

/// a[e] += Σ w · pixels[pixelOffset + p] over column e's entries whose pixel p lies in
/// `pixelsRead` (merged rows: one view's pixels; default all), for `only`'s elements (or all).
void hostAdjointAdd(const SparseRows& rows, const GpuVector& pixels, size_t pixelOffset, GpuVector& a, const Support* only,
                    Range pixelsRead = {});

}  // namespace volstyle::core
